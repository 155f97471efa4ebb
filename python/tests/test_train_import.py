"""The core package never imports torch; day2night.train's torch modules say how to get it."""

import subprocess
import sys


def run(code):
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)


def test_import_day2night_does_not_import_torch():
    r = run("import sys, day2night, day2night.train, day2night.train.preprocess, "
            "day2night.train.targets, day2night.train.scores\n"
            "assert 'torch' not in sys.modules, 'torch was imported'\nprint('ok')")
    assert r.returncode == 0 and "ok" in r.stdout, r.stderr


def test_missing_torch_names_the_extra():
    # torch made unimportable (a None entry in sys.modules makes `import torch` fail): the
    # torch modules import (their imports are at their tops), and the first use of torch
    # raises the ImportError that names the extra
    uses = {"unet": "m.UNet()", "data": "m.FixedPatches([], [])", "trainer": "m.collate([])",
            "infer": "import numpy as np\nclass Net:\n    def eval(self): pass\n"
                     "m.predict(Net(), np.zeros((16, 16, 3), np.float32), device='cpu')"}
    for mod, use in uses.items():
        r = run("import sys; sys.modules['torch'] = None\n"
                f"import day2night.train.{mod} as m\nprint('imported')\n{use}")
        assert "imported" in r.stdout, (mod, r.stderr)
        assert r.returncode != 0, mod
        assert "ImportError" in r.stderr and "pip install day2night[train]" in r.stderr, \
            (mod, r.stderr)
    r = run("import sys; sys.modules['torch'] = None\nimport day2night.train as t\nt.UNet()")
    assert "pip install day2night[train]" in r.stderr, r.stderr


def test_train_help_and_config_without_torch():
    # the trainer's settings and its command line need no torch: --help works without it
    r = run("import sys; sys.modules['torch'] = None\n"
            "from day2night.train.config import TrainConfig\n"
            "TrainConfig(out_dir='x').check()\n"
            "from day2night.train.__main__ import main\nmain(['--help'])")
    assert r.returncode == 0, r.stderr
    assert "--init-features" in r.stdout and "training epochs" in r.stdout, r.stdout


def test_experiment_help_without_torch():
    r = run("import sys; sys.modules['torch'] = None\n"
            "from day2night.experiment.__main__ import main\nmain(['--help'])")
    assert r.returncode == 0, r.stderr
    assert "--protocol" in r.stdout and "--folds-file" in r.stdout, r.stdout
    r = run("import sys; sys.modules['torch'] = None\n"
            "from day2night.experiment.runner import Experiment\n"
            "from day2night.experiment.config import ExperimentConfig\n"
            "Experiment(ExperimentConfig(day='d', real='r', output='o')).prepare()")
    assert "training needs torch" in r.stderr and "pip install day2night[train]" in r.stderr, \
        r.stderr


def test_a_damaged_torch_counts_as_missing(tmp_path):
    # a torch whose import raises OSError, as an install cut short leaves it (CI once had
    # torch/lib/libtorch_global_deps.so missing): the experiment's modules still import,
    # the torch-free rows' code runs, and the first use of torch names the extra and the
    # OSError
    fake = tmp_path / "torch"
    fake.mkdir()
    (fake / "__init__.py").write_text(
        "raise OSError('torch/lib/libtorch_global_deps.so: cannot open shared object file')\n")
    code = (f"import sys; sys.path.insert(0, {str(tmp_path)!r})\n"
            "from day2night.experiment import burst, pairs, prepare, rows\n"
            "import day2night.train as t\n"
            "from day2night.train import _torch\n"
            "assert not _torch.available()\n"
            "print('imported')\nt.UNet()")
    r = run(code)
    assert "imported" in r.stdout, r.stderr
    assert r.returncode != 0
    assert "pip install day2night[train]" in r.stderr, r.stderr
    assert "OSError: torch/lib/libtorch_global_deps.so" in r.stderr, r.stderr
