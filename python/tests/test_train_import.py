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
