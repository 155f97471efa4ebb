"""`python -m day2night.experiment` on the hostile inputs of issue 47: a malformed history or
initial validation, an epoch of 1e30, a PSNR of 1e308, --seeds 4294967296 and more folds
than scenes are each one line of error with exit status 2 that writes nothing (every file of
RUN unchanged, table.json, table.md and index.html not rewritten); a report that fails while
it is built leaves the earlier table and page as they were; a day DNG with a 250-byte stem
runs through (its cached pairs get a short stable name). A miniature run
(experiment_mini.py) is made once and copied per case. Needs torch and the CLI (D2N_BIN)."""

import hashlib
import json
import os
import shutil

import pytest

from conftest import need_torch

need_torch(module=True)  # skips (or fails) the module the trainer's tests' way

import experiment_mini as mini  # noqa: E402
from conftest import FIXTURES  # noqa: E402

OPTIONS = ["--epochs", 1, "--width", 4, "--task", "clean", "--rows", "ours", "supervised"]
UNIT = "clean/ours/all"
LONG_DAY = "d" * 250 + ".dng"


def env():
    e = dict(os.environ)
    e.setdefault("OMP_NUM_THREADS", "1")
    return e


@pytest.fixture(scope="module")
def base(tmp_path_factory, cli):
    root = tmp_path_factory.mktemp("hostile")
    day = mini.day_dir(root / "days", FIXTURES / "day.dng")
    shutil.copy(sorted(day.glob("*.dng"))[0], day / LONG_DAY)
    release, _ = mini.bursts(cli, root / "captures", FIXTURES / "day.dng")
    real = root / "real"
    cli("real-pairs", release, "-o", real)
    run = root / "run"
    mini.run_experiment(run, day, real, *OPTIONS, env=env())
    return {"root": root, "day": day, "real": real, "run": run}


def rerun(base, out, *extra):
    return mini.run_experiment(out, base["day"], base["real"], *OPTIONS, *extra, env=env(),
                               check=False)


def snapshot(out):
    """{relative path: (SHA-256, mtime)} of every file under ``out``."""
    return {str(p.relative_to(out)): (hashlib.sha256(p.read_bytes()).hexdigest(),
                                      p.stat().st_mtime_ns)
            for p in sorted(out.rglob("*")) if p.is_file()}


def assert_one_line_error(r, *needles):
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr, r.stderr
    errors = [ln for ln in r.stderr.splitlines() if "error" in ln.lower()]
    assert len(errors) == 1 and errors[0].startswith("day2night.experiment: error: "), r.stderr
    for n in needles:
        assert str(n) in errors[0], (n, r.stderr)


def test_a_250_byte_day_dng_stem_runs_with_short_cached_names(base):
    names = [p.name for p in (base["run"] / "data").rglob("*") if p.is_file()]
    assert all(len(n.encode()) <= 255 for n in names)
    long_ones = [n for n in names if n.startswith("d" * 100)]
    assert long_ones and all("~" in n for n in long_ones), long_ones
    assert (base["run"] / "table.json").is_file()


def _history(change):
    def edit(s):
        s["history"] = s["history"] or [{"epoch": 0, "loss": 0.1, "val_loss": 0.1}]
        change(s)
    return edit


HOSTILE = {
    "history [1]": (_history(lambda s: s.update(history=[1])), "not an object"),
    "entry without epoch": (_history(lambda s: s["history"][0].pop("epoch")), "epoch is None"),
    "epoch Infinity": (_history(lambda s: s["history"][0].update(epoch=float("inf"))),
                       "epoch is inf"),
    "epoch 1e30": (_history(lambda s: s["history"][0].update(epoch=10**30)),
                   "not a whole number"),
    "initial [1]": (lambda s: s.update(initial=[1]), "initial is [1]"),
    "PSNR 1e308": (lambda s: s["images"][0].update(psnr=1e308), "psnr 1e+308"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_hostile_unit_is_refused_before_anything_is_written(base, tmp_path, case):
    out = tmp_path / "run"
    shutil.copytree(base["run"], out, symlinks=True)
    path = out / "units" / UNIT / "scores.json"
    s = json.loads(path.read_text())
    HOSTILE[case][0](s)
    path.write_text(json.dumps(s))
    before = snapshot(out)
    r = rerun(base, out)
    assert_one_line_error(r, path, HOSTILE[case][1], f"--restart-unit {UNIT}")
    assert snapshot(out) == before


@pytest.mark.parametrize("extra,needle,resumed", [
    (["--seeds", 4294967296], "--seeds 4294967296: 1 to 1000", "--seeds 4294967296"),
    (["--seeds", 1001], "--seeds 1001: 1 to 1000", "--seeds 1001"),
    (["--folds", 7], "7 folds need at least 7 scenes", "made with folds = 3, not 7")])
def test_unbounded_work_is_refused_before_anything_is_written(base, tmp_path, extra, needle,
                                                              resumed):
    out = tmp_path / "run"
    shutil.copytree(base["run"], out, symlinks=True)
    before = snapshot(out)
    assert_one_line_error(rerun(base, out, *extra), resumed)
    assert snapshot(out) == before
    fresh = tmp_path / "fresh"
    assert_one_line_error(rerun(base, fresh, *extra), needle)
    assert not fresh.exists()


def test_a_report_that_fails_while_built_rewrites_nothing(base, tmp_path, monkeypatch,
                                                          capsys):
    from day2night.experiment import __main__ as cli_main
    from day2night.experiment import curves

    out = tmp_path / "run"
    shutil.copytree(base["run"], out, symlinks=True)
    for name in ("table.json", "table.md", "index.html"):
        (out / name).write_text(f"the earlier run's {name}\n")
    before = snapshot(out)

    def boom(*a, **k):
        raise RuntimeError("the curves failed")

    monkeypatch.setattr(curves, "svg", boom)
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    args = ["--day", str(base["day"]), "--real", str(base["real"]), "-o", str(out),
            *map(str, OPTIONS)]
    assert cli_main.main(args) == 1
    assert "the curves failed" in capsys.readouterr().err
    after = snapshot(out)
    for name in ("table.json", "table.md", "index.html"):
        assert after[name] == before[name], name
    monkeypatch.undo()
    assert cli_main.main(args) == 0
    assert (out / "table.json").read_bytes() == (base["run"] / "table.json").read_bytes()
