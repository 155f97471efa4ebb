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
    # torch made unimportable (a None entry in sys.modules makes `import torch` fail)
    for mod in ("unet", "data", "trainer", "infer"):
        r = run("import sys; sys.modules['torch'] = None\n"
                f"import day2night.train.{mod}")
        assert r.returncode != 0
        assert "ImportError" in r.stderr and "pip install day2night[train]" in r.stderr, r.stderr
    r = run("import sys; sys.modules['torch'] = None\nimport day2night.train as t\nt.train")
    assert "pip install day2night[train]" in r.stderr, r.stderr


def test_train_help_and_config_without_torch():
    # the trainer's settings and its command line need no torch: --help works without it
    r = run("import sys; sys.modules['torch'] = None\n"
            "from day2night.train.config import TrainConfig\n"
            "TrainConfig(out_dir='x').check()\n"
            "from day2night.train.__main__ import main\nmain(['--help'])")
    assert r.returncode == 0, r.stderr
    assert "--init-features" in r.stdout and "training epochs" in r.stdout, r.stdout
