"""`python -m day2night.experiment` on damaged run folders and bad inputs (issue 36, items 3,
4 and 10): every case is a clear error (exit 2, no traceback) naming the file and what to do,
and bad inputs leave nothing in RUN. A miniature run (experiment_mini.py: 6 real scenes of
124 x 124, UNet width 4, one epoch, the clean task, two rows) is made once and copied per case.
Needs torch (``pip install day2night[train]``) and the CLI (D2N_BIN)."""

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


def env():
    e = dict(os.environ)
    e.setdefault("OMP_NUM_THREADS", "1")
    return e


@pytest.fixture(scope="module")
def base(tmp_path_factory, cli):
    root = tmp_path_factory.mktemp("damaged")
    day = mini.day_dir(root / "days", FIXTURES / "day.dng")
    release, _ = mini.bursts(cli, root / "captures", FIXTURES / "day.dng")
    real = root / "real"
    cli("real-pairs", release, "-o", real)
    run = root / "run"
    mini.run_experiment(run, day, real, *OPTIONS, env=env())
    return {"root": root, "day": day, "real": real, "run": run}


def rerun(base, out, *extra, day=None, real=None):
    return mini.run_experiment(out, day or base["day"], real or base["real"], *OPTIONS, *extra,
                               env=env(), check=False)


def copy_run(base, tmp_path):
    out = tmp_path / "run"
    shutil.copytree(base["run"], out, symlinks=True)
    return out


def assert_clear_error(r, *needles):
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr, r.stderr
    for n in needles:
        assert str(n) in r.stderr, (n, r.stderr)


WRONG_JSON = {"list": "[]", "string": '"x"', "number": "7", "null": "null",
              "garbage": "{not json", "empty": ""}


@pytest.mark.parametrize("kind", sorted(WRONG_JSON))
@pytest.mark.parametrize("name", ["config.json", "folds.json"])
def test_damaged_setup_file_is_a_clear_error(base, tmp_path, name, kind):
    out = copy_run(base, tmp_path)
    (out / name).write_text(WRONG_JSON[kind])
    r = rerun(base, out)
    assert_clear_error(r, out / name, "delete it and rerun")


def test_fold_manifest_of_other_folds_is_a_clear_error(base, tmp_path):
    out = copy_run(base, tmp_path)
    f = json.loads((out / "folds.json").read_text())
    f["splits"][0]["fold"] = 7  # a fold number the mixes cannot be indexed with
    (out / "folds.json").write_text(json.dumps(f))
    assert_clear_error(rerun(base, out), out / "folds.json", "damaged fold manifest")


SCORES = {"list": "[]", "garbage": "\x00\x01garbage", "empty-object": "{}",
          "string-scores": None, "missing-image": None}


@pytest.mark.parametrize("kind", sorted(SCORES))
def test_damaged_scores_is_a_clear_error(base, tmp_path, kind):
    out = copy_run(base, tmp_path)
    path = out / "units" / UNIT / "scores.json"
    text = SCORES[kind]
    if text is None:
        s = json.loads(path.read_text())
        if kind == "string-scores":
            s["images"][0]["psnr"] = "high"
        else:
            s["images"].pop()
        text = json.dumps(s)
    path.write_text(text)
    r = rerun(base, out)
    assert_clear_error(r, path, f"--restart-unit {UNIT}", out / "units" / UNIT)


def first_cached(out):
    return sorted((out / "data" / "real").glob("*.in.npy"))[0]


@pytest.mark.parametrize("damage", ["empty", "truncated", "empty-target"])
def test_damaged_cached_array_is_a_clear_error(base, tmp_path, damage):
    out = copy_run(base, tmp_path)
    (out / "units" / UNIT / "scores.json").unlink()  # the unit reads the cache again
    path = first_cached(out)
    if damage == "empty-target":
        path = path.with_name(path.name.replace(".in.npy", ".y.npy"))
    data = path.read_bytes()
    path.write_bytes(b"" if damage.startswith("empty") else data[: len(data) // 2])
    r = rerun(base, out)
    assert_clear_error(r, path, "damaged cached array", "delete it and rerun")


@pytest.mark.parametrize("name", ["last.pt", "best.pt"])
def test_truncated_checkpoint_is_a_clear_error_and_restart_unit_retrains(base, tmp_path, name):
    out = copy_run(base, tmp_path)
    (out / "units" / UNIT / "scores.json").unlink()  # not done: its checkpoints are read
    path = out / "units" / UNIT / "model" / name
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    r = rerun(base, out)
    assert_clear_error(r, path, "damaged checkpoint", "no earlier checkpoint",
                       f"--restart-unit {UNIT}")
    r = rerun(base, out, "--restart-unit", UNIT)
    assert r.returncode == 0, r.stderr
    assert f"--restart-unit {UNIT}: deleted" in r.stderr
    # the retrained unit gives the uninterrupted run's table, byte for byte
    assert (out / "table.json").read_bytes() == (base["run"] / "table.json").read_bytes()


@pytest.mark.parametrize("damage", ["best-missing", "model-is-a-file", "epoch-past-the-end"])
def test_unusable_model_folder_is_a_clear_error(base, tmp_path, damage):
    import torch

    out = copy_run(base, tmp_path)
    unit = out / "units" / UNIT
    (unit / "scores.json").unlink()
    if damage == "best-missing":
        (unit / "model" / "best.pt").unlink()
        needle = unit / "model" / "best.pt"
    elif damage == "model-is-a-file":
        shutil.rmtree(unit / "model")
        (unit / "model").write_text("x")
        needle = unit / "model"
    else:
        ck = torch.load(unit / "model" / "last.pt", weights_only=True)
        ck["epoch"] = 5
        torch.save(ck, unit / "model" / "last.pt")
        needle = "epoch 5"
    assert_clear_error(rerun(base, out), needle, f"--restart-unit {UNIT}")


def test_restart_unit_must_name_a_unit_of_the_run(base, tmp_path):
    out = copy_run(base, tmp_path)
    r = rerun(base, out, "--restart-unit", "noisy/ours/all")
    assert_clear_error(r, "--restart-unit noisy/ours/all: not a unit of this run", UNIT)


def assert_nothing_written(out):
    written = sorted(str(p.relative_to(out)) for p in out.rglob("*")) if out.exists() else []
    assert written == [], f"files written despite the error: {written}"


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_unreadable_day_dng_writes_nothing(base, tmp_path, damage):
    day = tmp_path / "days"
    shutil.copytree(base["day"], day)
    victim = sorted(day.glob("*.dng"))[-1]
    data = victim.read_bytes()
    victim.write_bytes(b"not a DNG at all" if damage == "garbage" else data[: len(data) // 3])
    out = tmp_path / "run"
    r = rerun(base, out, day=day)
    assert_clear_error(r, victim)
    assert_nothing_written(out)


def real_copy(base, tmp_path):
    real = tmp_path / "real"
    shutil.copytree(base["real"], real)
    return real


def set_manifest_output(real, path, **fields):
    """Rewrite the manifest record of ``path`` (real-pairs' fields: bytes, sha256)."""
    m = real / "manifest.jsonl"
    recs = [json.loads(line) for line in m.read_text().splitlines() if line.strip()]
    rel = path.relative_to(real).as_posix()
    hits = [o for r in recs for o in r.get("outputs", []) if o["path"] == rel]
    assert len(hits) == 1, rel
    hits[0].update(fields)
    m.write_text("".join(json.dumps(r) + "\n" for r in recs))


@pytest.mark.parametrize("damage", ["text", "small", "truncated"])
def test_unreadable_real_target_writes_nothing(base, tmp_path, damage):
    from day2night.png import png_bytes

    import numpy as np

    real = real_copy(base, tmp_path)
    victim = sorted((real / "real" / "target").glob("*.png"))[2]
    data = {"text": b"a text file, not a PNG\n",
            "small": png_bytes(np.zeros((10, 30, 3), np.uint8)),
            "truncated": victim.read_bytes()[:-40]}[damage]
    victim.write_bytes(data)
    # the manifest agrees with the file (a target copied without a check, as item 2 found)
    set_manifest_output(real, victim, bytes=len(data), sha256=hashlib.sha256(data).hexdigest())
    out = tmp_path / "run"
    r = rerun(base, out, real=real)
    assert_clear_error(r, victim)
    assert_nothing_written(out)


@pytest.mark.parametrize("what", ["target", "clean_raw"])
def test_edited_manifest_sha256_is_refused(base, tmp_path, what):
    real = real_copy(base, tmp_path)
    folder = "target" if what == "target" else "clean_raw"
    victim = sorted((real / "real" / folder).iterdir())[1]
    set_manifest_output(real, victim, sha256="0" * 64)
    out = tmp_path / "run"
    r = rerun(base, out, real=real)
    assert_clear_error(r, victim, "SHA-256", "real-pairs")
    assert_nothing_written(out)


@pytest.mark.parametrize("option,value", [("--seed", -1), ("--seed", 2**32), ("--show", -1)])
def test_out_of_range_option_names_the_option(base, tmp_path, option, value):
    out = tmp_path / "run"
    r = rerun(base, out, option, value)
    assert_clear_error(r, f"{option} {value}")
    assert_nothing_written(out)


@pytest.mark.parametrize("line", ["[]", "7", '"scene"'])
def test_manifest_line_that_is_not_an_object_is_a_clear_error(base, tmp_path, line):
    """A real set's manifest.jsonl line that is valid JSON but not an object is refused with
    the manifest's name (it once crashed in the --targets default, before the real set's own
    checks ran)."""
    real = real_copy(base, tmp_path)
    m = real / "manifest.jsonl"
    m.write_text(line + "\n" + m.read_text(encoding="utf-8"), encoding="utf-8")
    out = tmp_path / "run"
    r = rerun(base, out, real=real)
    assert_clear_error(r, "manifest.jsonl")
    assert_nothing_written(out)
