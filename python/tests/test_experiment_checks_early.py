"""What the experiment checks before it writes anything (issue 47, items 2 and 3), on hand-made
files (numpy only; the whole command line: test_experiment_hostile.py): a unit's history,
initial validation and scores against their ranges, the --seeds bound, the folds, and the
short stable file names of long scene ids and day-image stems."""

import dataclasses
import json

import pytest

from day2night.experiment import folds as folds_mod
from day2night.experiment import names, runfolder, scorecheck
from day2night.experiment.config import MAX_SEEDS, ExperimentConfig, ExperimentError

SCENES = ["s0", "s1"]
GOOD = {"task": "clean", "row": "ours", "fold": "all", "test_scenes": SCENES,
        "history": [{"epoch": 0, "loss": 0.1, "val_loss": 0.09, "val_psnr": 20.5, "lr": 1e-3},
                    {"epoch": 1, "loss": "nan", "val_loss": 0.08, "val_psnr": 21.0,
                     "lr": 1e-3}],
        "initial": {"val_loss": 0.3, "val_psnr": 9.0},
        "images": [{"scene": s, "input": "clean", "psnr": 30.0, "ssim": 0.9, "delta_e": 3.0}
                   for s in SCENES]}
# (what to change, text the error must hold): the hostile inputs and their kin
HOSTILE = {
    "history [1]": (lambda u: u.update(history=[1]), "not an object"),
    "entry without epoch": (lambda u: u["history"][0].pop("epoch"), "epoch is None"),
    "epoch Infinity": (lambda u: u["history"][0].update(epoch=float("inf")), "epoch is inf"),
    "epoch 1e30": (lambda u: u["history"][0].update(epoch=10**30), "not a whole number"),
    "epoch 2.0": (lambda u: u["history"][0].update(epoch=2.0), "not a whole number"),
    "epochs not increasing": (lambda u: u["history"][1].update(epoch=0), "strictly"),
    "loss 1e308": (lambda u: u["history"][0].update(loss=1e308), "loss is 1e+308"),
    "negative loss": (lambda u: u["history"][0].update(val_loss=-1.0), "val_loss is -1.0"),
    "loss as text": (lambda u: u["history"][0].update(loss="x"), "loss is x"),
    "history null": (lambda u: u.update(history=None), "no history list"),
    "initial [1]": (lambda u: u.update(initial=[1]), "initial is [1]"),
    "initial 1e300": (lambda u: u["initial"].update(val_psnr=1e300), "val_psnr is 1e+300"),
    "PSNR 1e308": (lambda u: u["images"][0].update(psnr=1e308), "psnr 1e+308"),
    "PSNR -1": (lambda u: u["images"][0].update(psnr=-1.0), "psnr -1.0"),
    "PSNR -inf": (lambda u: u["images"][0].update(psnr="-inf"), "psnr -inf"),
    "SSIM 1.5": (lambda u: u["images"][1].update(ssim=1.5), "ssim 1.5"),
    "SSIM inf": (lambda u: u["images"][1].update(ssim="inf"), "ssim inf"),
    "Delta E -0.1": (lambda u: u["images"][1].update(delta_e=-0.1), "delta_e -0.1"),
    "Delta E 1e6": (lambda u: u["images"][1].update(delta_e=1e6), "delta_e 1000000.0"),
}


def _write(tmp_path, unit):
    path = runfolder.unit_dir(tmp_path, "clean/ours/all") / "scores.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(unit))  # allow_nan: Infinity as JSON writes it
    return path


def _read(tmp_path, path, epochs=2):
    return runfolder.read_scores(tmp_path, path, "clean", "ours", "all", ["clean"], SCENES,
                                 epochs=epochs)


def test_a_sound_unit_passes_with_inf_psnr_and_a_diverged_epoch(tmp_path):
    unit = json.loads(json.dumps(GOOD))
    unit["images"][0]["psnr"] = "inf"
    assert _read(tmp_path, _write(tmp_path, unit))["history"][1]["loss"] == "nan"
    del unit["initial"]  # a unit of an earlier version: no initial
    _read(tmp_path, _write(tmp_path, unit))


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_hostile_unit_is_one_line_naming_the_file_and_the_fix(tmp_path, case):
    change, needle = HOSTILE[case]
    unit = json.loads(json.dumps(GOOD))
    change(unit)
    path = _write(tmp_path, unit)
    with pytest.raises(runfolder.RunFolderError) as e:
        _read(tmp_path, path)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{path}: damaged unit scores")
    assert needle in msg and "--restart-unit clean/ours/all" in msg


def test_an_epoch_past_the_runs_epochs_is_refused(tmp_path):
    path = _write(tmp_path, GOOD)
    _read(tmp_path, path, epochs=2)
    with pytest.raises(runfolder.RunFolderError, match="from 0 to 0"):
        _read(tmp_path, path, epochs=1)
    assert scorecheck.history_problem([{"epoch": scorecheck.EPOCH_MAX}]) is not None


@pytest.mark.parametrize("seeds,ok", [(1, True), (MAX_SEEDS, True), (MAX_SEEDS + 1, False),
                                      (10**6, False), (4294967296, False)])
def test_seeds_are_bounded(seeds, ok):
    c = dataclasses.replace(ExperimentConfig(day="d", real="r", output="o"), seeds=seeds)
    if ok:
        c.with_preset().check()
    else:
        with pytest.raises(ExperimentError, match=f"--seeds {seeds}: 1 to {MAX_SEEDS}"):
            c.with_preset().check()


@pytest.mark.parametrize("n,k", [(4, 5), (1, 2), (6, 7)])
def test_more_folds_than_scenes_are_refused(n, k):
    with pytest.raises(folds_mod.FoldError, match=f"{k} folds need at least {k} scenes"):
        folds_mod.make_folds([f"s{i}" for i in range(n)], k)


def test_a_fold_without_test_scenes_is_refused():
    m = folds_mod.make_folds([f"s{i}" for i in range(6)], 2)
    m["splits"][1]["train"] += m["splits"][1]["test"]
    m["splits"][1]["test"] = []
    with pytest.raises(folds_mod.FoldError, match="fold 1: an empty train, val or test list"):
        folds_mod.check_folds(m)


def _fits(stem, suffix):
    """Whether ``stem + suffix`` and its temporary name (atomic.py) fit in a file name."""
    return len((stem + suffix).encode()) + names.TEMP_EXTRA <= names.NAME_MAX


def test_long_names_become_short_stable_distinct_file_names():
    day = "d" * 250 + ".dng"  # a legal 254-byte day DNG name (250-byte stem)
    stem = names.day_stem(day)
    assert _fits(stem, "_3200.in.npy") and _fits(stem, ".y.npy") and stem == names.day_stem(day)
    assert stem.startswith("d" * 100) and "~" in stem
    assert names.day_stem("d" * 249 + "e.dng") != stem  # same first bytes, another file
    assert names.day_stem("sub/day_00.dng") == "sub__day_00"  # short names are unchanged
    link = names.day_link("a" * 200 + "/" + "b" * 200 + ".DNG")
    assert len(link.encode()) <= 255 and link.endswith(".DNG")
    sid = "n" * 225  # a 225-byte scene id (an older real-pairs, or a hand-made real set)
    for key in ("clean", "1600"):
        s = names.image_stem(sid, key)
        assert all(_fits(s, x) for x in ("_target.png", "_input.png", "_pred.png", "_de.png"))
    assert _fits(names.scene_stem(sid) + "_3200", ".in.npy")
    assert names.scene_stem("n" * names.SCENE_ROOM) == "n" * names.SCENE_ROOM
    wide = "é" * 150  # 300 bytes: cut on a character boundary
    assert names.scene_stem(wide).encode().decode() == names.scene_stem(wide)
    assert len(names.scene_stem(wide).encode()) <= names.SCENE_ROOM
