"""The experiment's uncertainty (issue 41): the seeded bootstrap of stats.py on known cases,
and table.json / table.md of a hand-made run folder (no training: numpy only)."""

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest

from day2night.experiment import config as config_mod
from day2night.experiment import runfolder, stats, table
from day2night.experiment.config import ExperimentConfig, ExperimentError
from day2night.experiment.rows import Row


def test_a_constant_difference_gives_a_zero_width_interval_at_it():
    for seeds in (1, 3):
        d = np.full((seeds, 17), 0.37)
        s = stats.summary(d, folds=np.arange(17) % 3, seed=4)
        assert s["mean"] == s["ci_low"] == s["ci_high"] == 0.37
        assert s["n_scenes"] == 17
    c = stats.compare(np.full(9, 30.5), np.full(9, 30.0), "psnr", seed=2)
    assert (c["mean"], c["ci_low"], c["ci_high"], c["verdict"]) == (0.5, 0.5, 0.5, "better")


def test_the_interval_covers_the_true_mean_at_about_the_stated_rate():
    # 400 seeded repetitions of n = 40 normal differences (mean 0.3, sd 1): a 95 % interval
    # covers 0.3 in 380 +- 3 binomial sd (4.4) of them; the percentile bootstrap undercovers a
    # little at n = 40, so the band is [0.95 - 3 sd, 0.95 + 3 sd] in counts.
    rng = np.random.default_rng(2022)
    covered = 0
    for rep in range(400):
        d = rng.normal(0.3, 1.0, 40)
        s = stats.summary(d, seed=rep, replicates=2000)
        covered += s["ci_low"] <= 0.3 <= s["ci_high"]
    sd = math.sqrt(400 * 0.95 * 0.05)
    assert 380 - 3 * sd <= covered <= 380 + 3 * sd, covered


def test_one_scene_per_fold_gives_no_interval_and_no_verdict():
    # issue 47: 4 folds of 4 scenes resampled within folds gave "32.05 [32.05, 32.05]" and a
    # verdict for any difference; now: too few scenes, no interval, no verdict
    v = np.array([32.05, 31.53, 32.39, 32.22])
    for folds in ([0, 1, 2, 3], [0, 0, 1, 2]):  # --folds 4, and the default 3, on 4 scenes
        s = stats.summary(v, folds=folds, seed=1)
        assert (s["ci_low"], s["ci_high"], s["note"]) == (None, None, stats.TOO_FEW)
        assert s["mean"] == pytest.approx(v.mean())
        c = stats.compare(v, v - 0.5, "psnr", folds=folds, seed=1)
        assert (c["ci_low"], c["verdict"], c["note"]) == (None, None, stats.TOO_FEW)
    assert stats.summary(v[:2], seed=1)["note"] == stats.TOO_FEW  # under 3 scenes in all
    s = stats.summary(v, folds=[0, 0, 1, 1], seed=1)
    assert s["ci_low"] < v.min() and s["ci_high"] > v.max()  # n = 4: the t interval


def test_a_per_fold_row_is_resampled_across_the_test_set_with_its_fold_weights():
    # fold 0: 2 scenes at 0, fold 1: 3 scenes at 1; the row's mean is the mean of its fold
    # means (0.5, not the scenes' 0.6) and its interval no longer collapses to a point
    v = np.array([0.0, 0.0, 1.0, 1.0, 1.0])
    w = [5 / 4, 5 / 4, 5 / 6, 5 / 6, 5 / 6]
    s = stats.summary(v, folds=[0, 0, 1, 1, 1], weights=w, seed=3)
    assert s["mean"] == pytest.approx(0.5) and s["seed_means"] == [pytest.approx(0.5)]
    assert s["ci_low"] < 0.2 and s["ci_high"] > 0.8
    reps = stats.replicates_of(v, w, seed=3, replicates=2000)
    assert reps.min() == 0.0 and reps.max() == 1.0  # a replicate may draw one fold only
    # a synthetic row (weights 1) against it: the difference of the two weighted means
    c = stats.compare(np.full(5, 0.7), v, "psnr", folds=[0, 0, 1, 1, 1], weights=(None, w))
    assert c["mean"] == pytest.approx(0.2)


def test_zero_seeds_and_huge_values_give_no_exception_and_no_nan():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = stats.summary(np.zeros((0, 5)))
        assert (s["mean"], s["ci_low"], s["note"]) == (None, None, "no seeds")
        c = stats.compare(np.zeros((0, 5)), np.ones((2, 5)), "psnr")
        assert c["mean"] is None and c["verdict"] == "not distinguishable"
        for v in ([1e308, 1e308, 1e308], [1e308, -1e308, 1e308, 5.0], [1e101, 1.0, 2.0]):
            s = stats.summary(v)
            assert s["ci_low"] is None and s["note"] == stats.TOO_LARGE
            assert isinstance(s["mean"], float) and math.isfinite(s["mean"])
        c = stats.compare([1e308] * 4, [-1e308] * 4, "psnr")
        assert c["mean"] == "inf" and c["ci_low"] is None
        s = stats.summary([1e90, 2e90, 3e90, 4e90])
        assert math.isfinite(s["ci_low"]) and s["ci_low"] < 2.5e90 < s["ci_high"]
        json.dumps([s, c], allow_nan=False)


def test_the_t_quantile_is_students():
    from day2night.experiment import tdist

    for df, want in ((1, 12.7062), (2, 4.3027), (3, 3.1824), (5, 2.5706), (11, 2.2010),
                     (30, 2.0423), (1e6, 1.9600)):
        assert tdist.quantile(0.95, df) == pytest.approx(want, abs=1e-4)
    assert tdist.quantile(0.90, 4) == pytest.approx(2.1318, abs=1e-4)


def test_seeds_that_disagree_widen_the_interval():
    rng = np.random.default_rng(5)
    scenes = rng.normal(0.0, 1.0, 30)
    agree = np.stack([scenes, scenes, scenes])
    disagree = np.stack([scenes - 2.0, scenes, scenes + 2.0])
    a = stats.summary(agree, seed=1)
    b = stats.summary(disagree, seed=1)
    assert a["mean"] == pytest.approx(b["mean"])
    assert (b["ci_high"] - b["ci_low"]) > 2 * (a["ci_high"] - a["ci_low"])
    assert a["seed_sd"] == 0.0 and b["seed_sd"] == pytest.approx(2.0)
    assert b["seed_means"] == pytest.approx([scenes.mean() - 2, scenes.mean(), scenes.mean() + 2])
    assert stats.summary(scenes, seed=1)["seed_sd"] is None


@pytest.mark.parametrize("metric,lower,want", [
    ("delta_e", True, "better"), ("delta_e", False, "worse"),
    ("psnr", True, "worse"), ("psnr", False, "better"), ("ssim", False, "better")])
def test_the_verdict_follows_the_metrics_direction(metric, lower, want):
    rng = np.random.default_rng(7)
    ref = rng.normal(5.0, 1.0, 25)
    row = ref + (-1.0 if lower else 1.0) + rng.normal(0, 0.1, 25)
    assert stats.compare(row, ref, metric, seed=0)["verdict"] == want
    noise = ref + rng.normal(0, 0.5, 25) * np.sign(rng.normal(size=25))
    assert stats.compare(ref + (noise - noise.mean()), ref, metric)["verdict"] == \
        "not distinguishable"


def test_infinite_and_undefined_scores_have_no_interval_and_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = stats.summary([40.0, math.inf, 38.0])
        assert (s["mean"], s["ci_low"], s["ci_high"]) == ("inf", None, None)
        assert "infinite" in s["note"]
        c = stats.compare([math.inf, 40.0], [math.inf, 39.0], "psnr")
        assert c["mean"] == "nan" and c["verdict"] == "not distinguishable"
        s = stats.summary([[1.0, 2.0], [math.inf, 1.0]])
        assert s["seed_means"] == [1.5, "inf"] and s["seed_sd"] is None
        json.dumps([s, c], allow_nan=False)


def test_a_row_with_one_series_pairs_with_each_seed():
    a = np.array([[1.0, 2.0, 3.0]])
    b = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    assert stats.paired(a, b).tolist() == [[1, 2, 3], [0, 1, 2]]
    with pytest.raises(ValueError, match="scenes"):
        stats.paired(a, b[:, :2])


def test_the_bootstrap_is_seeded():
    v = np.random.default_rng(0).normal(size=(2, 20))
    assert stats.summary(v, seed=9) == stats.summary(v, seed=9)
    assert stats.summary(v, seed=9) != stats.summary(v, seed=10)
    assert stats.bootstrap_seed(0) != stats.bootstrap_seed(1)


# --- the label, the options ---------------------------------------------------------------

BASE = ExperimentConfig(day="d", real="r", output="o")


@pytest.mark.parametrize("opts,label", [
    ({}, "paper"), ({"preset": "mini"}, "mini"), ({"width": 4, "epochs": 3}, "smoke"),
    ({"preset": "mini", "width": 4, "epochs": 3}, "smoke"),
    ({"preset": "mini", "epochs": 3}, "custom"), ({"width": 4}, "custom"),
    ({"preset": "mini", "lr": 1e-3}, "custom")])
def test_the_label_names_the_preset(opts, label):
    assert dataclasses.replace(BASE, **opts).with_preset().label == label


def test_seeds_are_recorded_only_when_more_than_one():
    c = BASE.with_preset()
    assert "seeds" not in c.record() and c.seed_list == [0]
    c = dataclasses.replace(c, seed=5, seeds=3)
    assert c.record()["seeds"] == 3 and c.seed_list == [5, 6, 7]
    assert "compare_to" not in dataclasses.replace(c, compare_to="ours").record()


@pytest.mark.parametrize("opts,msg", [({"seeds": 0}, "--seeds 0"),
                                      ({"seed": 2**32 - 1, "seeds": 2}, "--seeds 2"),
                                      ({"compare_to": "nope"}, "--compare-to: unknown row")])
def test_bad_seeds_and_reference_are_refused(opts, msg):
    with pytest.raises(ExperimentError, match=msg):
        dataclasses.replace(BASE, **opts).with_preset().check()
    dataclasses.replace(BASE, compare_to="untrained").with_preset().check()


def test_extra_seeds_units_live_apart():
    assert runfolder.unit_id("clean", "ours", "all") == "clean/ours/all"
    uid = runfolder.unit_id("noisy", "mix5", "1", 4)
    assert uid == "seed-4/noisy/mix5/1"
    assert runfolder.unit_dir("/r", uid).as_posix() == "/r/seeds/4/units/noisy/mix5/1"
    assert runfolder.unit_dir("/r", "clean/ours/all").as_posix() == "/r/units/clean/ours/all"
    assert "seeds" in config_mod.CONFIG_KEYS


# --- table.json of a hand-made run folder ---------------------------------------------------

SPLITS = [{"fold": 0, "train": ["s2", "s3"], "val": ["s4"], "test": ["s0", "s1"]},
          {"fold": 1, "train": ["s0", "s4"], "val": ["s1"], "test": ["s2", "s3", "s4"]}]
SCENES = ["s0", "s1", "s2", "s3", "s4"]
# (the burst row 5 dB under day: beyond the two seeds' 0.5 dB spread, which the interval's
# Welch-Satterthwaite degrees of freedom, about 1, widen by a t factor of about 10)
BASE_PSNR = {"untrained": 10.0, "day": 30.0, "ours": 31.0, "mix5": 30.0, "burst": 25.0}


def _unit(out, task, row, fold, tests, seed, base_seed, psnr):
    keys = ["clean"] if task == "clean" else ["1600", "3200"]
    images = [{"scene": s, "input": k, "psnr": psnr(s, k), "ssim": 0.9, "delta_e": 3.0}
              for s in tests for k in keys]
    rec = {"task": task, "row": row, "fold": fold, "history": [], "initial": {},
           "images": images, "test_scenes": tests}
    extra = seed is not None and seed != base_seed
    uid = runfolder.unit_id(task, row, fold, seed if extra else None)
    path = runfolder.unit_dir(out, uid) / "scores.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rec))


def _run_folder(out, seeds, rows, task="clean", burst=False):
    for seed in seeds:
        for row in ["untrained"] + rows:
            def psnr(s, k, row=row, seed=seed):
                if row == "ours" and s == "s0" and seed == seeds[0]:
                    return "inf"  # an identical prediction: no interval for that cell
                return BASE_PSNR[row] + 0.1 * int(s[1]) + 0.5 * (seed - seeds[0]) \
                    + (0.3 if k == "3200" else 0.0)
            if row == "mix5":
                for sp in SPLITS:
                    _unit(out, task, row, str(sp["fold"]), sp["test"], seed, seeds[0], psnr)
            else:
                _unit(out, task, row, "all", SCENES, seed, seeds[0], psnr)
    if burst:
        _unit(out, "noisy", "burst", "all", SCENES, None, None,
              lambda s, k: BASE_PSNR["burst"] + 0.2 * int(s[1]))


def _config(seeds, rows, task="clean", **kw):
    kw = {"targets": "day2night", "noise": "day2night", "protocol": "day2night",
          "synth_iso": "alternate", **kw}
    kw = {"width": 4, "epochs": 3, "compare_to": "day", **kw}
    return dataclasses.replace(BASE, seed=seeds[0], seeds=len(seeds), rows=tuple(rows),
                               task=task, folds=2, **kw).with_preset()


def test_table_json_has_scores_gains_and_comparisons(tmp_path):
    rows = ["day", "ours", "mix5"]
    _run_folder(tmp_path, [3, 4], rows)
    t = table.build(_config([3, 4], rows), tmp_path, SPLITS, 5, 4)
    json.dumps(t, allow_nan=False)
    assert t["format"] == "day2night-experiment-table/2" and t["label"] == "smoke"
    assert t["seeds"] == [3, 4] and t["compare_to"] == "day"
    assert t["bootstrap"]["replicates"] == stats.REPLICATES and t["bootstrap"]["level"] == 0.95
    assert set(t["protocol"]) == {"protocol", "targets", "noise", "synth_iso", "amp",
                                  "channels_last", "folds_file"}
    assert [(r["row"], r["kind"]) for r in t["rows"]] == [
        ("untrained", "untrained"), ("day", "trained"), ("ours", "trained"),
        ("mix5", "trained")]
    un, day, ours, mix5 = t["rows"]
    assert un["gain"] is None and un["paper"] is None
    assert day["paper"] == {"clean": {"psnr": 41.16, "ssim": 0.9713, "delta_e": 1.2369}}
    s = day["scores"]["clean"]["psnr"]
    assert s["seeds"] == [3, 4] and s["n_scenes"] == 5
    assert s["seed_means"] == pytest.approx([30.2, 30.7]) and s["mean"] == pytest.approx(30.45)
    assert s["ci_low"] <= s["mean"] <= s["ci_high"]
    assert day["mean"]["clean"]["psnr"] == pytest.approx(30.45)
    assert [u["seed"] for u in mix5["units"]] == [3, 3, 4, 4]
    # the per-fold row's mean is the mean of its fold means (fold 0: 30.05, fold 1: 30.3)
    assert mix5["scores"]["clean"]["psnr"]["seed_means"][0] == pytest.approx(30.175)
    assert mix5["mean"]["clean"]["psnr"] == pytest.approx(30.425)
    # every seed is 20 dB above the untrained row on every scene: a zero-width gain
    g = day["gain"]["clean"]["psnr"]
    assert g["mean"] == g["ci_low"] == pytest.approx(20.0) == g["ci_high"]
    assert ours["scores"]["clean"]["psnr"]["mean"] == "inf"
    assert ours["scores"]["clean"]["psnr"]["ci_low"] is None
    comps = {(c["row"], c["metric"]): c for c in t["comparisons"]}
    assert {c["row"] for c in t["comparisons"]} == {"untrained", "ours", "mix5"}
    assert comps[("untrained", "psnr")]["verdict"] == "worse"
    assert comps[("ours", "delta_e")]["verdict"] == "not distinguishable"
    # the same SSIM in every unit, weighted by fold sizes 2 and 3: exactly no difference
    assert (comps[("mix5", "ssim")]["mean"], comps[("mix5", "ssim")]["verdict"]) == \
        (0.0, "not distinguishable")
    assert comps[("ours", "psnr")]["ci_low"] is None
    assert all(c["reference"] == "day" and c["seeds"] == [3, 4] for c in t["comparisons"])
    md = table.markdown(t)
    assert "**Smoke run**" in md and "Training seeds: 3, 4" in md
    assert "30.45 [" in md and "gain over untrained (PSNR / SSIM / Delta E)" in md
    assert "+20.00 [" in md
    assert "### Comparisons against Day (clean task)" in md and "| worse |" in md
    assert "5 test scenes" in md and "inf (a test scene's value is infinite" in md


def test_one_seed_table_keeps_the_first_formats_means(tmp_path):
    _run_folder(tmp_path, [0], ["day"])
    t = table.build(_config([0], ["day"]), tmp_path, SPLITS, 5, 4)
    day = t["rows"][1]
    assert day["mean"]["clean"]["psnr"] == pytest.approx(30.2, abs=1e-12)
    assert day["scores"]["clean"]["psnr"]["seed_sd"] is None
    assert [u["seed"] for u in day["units"]] == [0]
    assert not (tmp_path / "seeds").exists()


def test_the_burst_row_is_scored_or_left_out_with_the_reason(tmp_path, monkeypatch):
    burst = Row("burst", "Burst denoising (mean of the high-ISO frames)", "burst")
    real_select = table.select
    monkeypatch.setattr(table, "select",
                        lambda ids: real_select([i for i in ids if i != "burst"])
                        + ([burst] if "burst" in ids else []))
    rows = ["day", "burst"]
    _run_folder(tmp_path, [0, 1], ["day"], task="noisy")
    cfg = _config([0, 1], rows, task="noisy")
    t = table.build(cfg, tmp_path, SPLITS, 5, 4)
    assert [r["row"] for r in t["rows"]] == ["untrained", "day"]
    assert t["left_out"] == [{"task": "noisy", "row": "burst", "why": table.BURST_MISSING}]
    assert "Left out: burst (noisy task)" in table.markdown(t)
    _run_folder(tmp_path, [0, 1], ["day"], task="noisy", burst=True)
    t = table.build(cfg, tmp_path, SPLITS, 5, 4)
    b = t["rows"][-1]
    assert (b["row"], b["kind"], b["units"][0]["seed"]) == ("burst", "burst", None)
    assert b["scores"]["1600"]["psnr"]["seeds"] == []
    assert b["paper"] == {"1600": {"psnr": 34.91, "ssim": 0.8021},
                          "3200": {"psnr": 31.39, "ssim": 0.6526}}
    assert b["gain"]["1600"]["psnr"]["mean"] == pytest.approx(14.95)
    c = [c for c in t["comparisons"] if c["row"] == "burst" and c["metric"] == "psnr"]
    assert [x["input"] for x in c] == ["1600", "3200"] and c[0]["verdict"] == "worse"
    assert t["left_out"] == []
    why = {"task": "noisy", "row": "burst", "why": "one frame per ISO"}
    t = table.build(cfg, tmp_path, SPLITS, 5, 4, left_out=[why])
    assert [r["row"] for r in t["rows"]] == ["untrained", "day"] and t["left_out"] == [why]


def test_the_fresh_row_left_out_by_the_protocol_is_named(tmp_path):
    _run_folder(tmp_path, [0], ["day"])
    cfg = _config([0], ["day"], targets="release", noise="release")
    t = table.build(cfg, tmp_path, SPLITS, 5, 4)
    assert t["left_out"] == [{"task": "clean", "row": "fresh", "why": table.FRESH_WHY}]


def test_an_extra_seeds_unit_is_checked_named_and_restarted_apart(tmp_path):
    from day2night.experiment import prepare, rows
    from day2night.experiment.runfolder import RunFolderError

    _run_folder(tmp_path, [0, 1], ["day"])
    work = rows.work(["clean"], [rows.UNTRAINED, rows.BY_ID["day"]], SPLITS)
    prepare.check_run_folder(tmp_path, work, (), SCENES, 3, [1])
    bad = tmp_path / "seeds" / "1" / "units" / "clean" / "day" / "all" / "scores.json"
    bad.write_text("[]")
    with pytest.raises(RunFolderError, match="--restart-unit seed-1/clean/day/all") as e:
        prepare.check_run_folder(tmp_path, work, (), SCENES, 3, [1])
    assert str(bad) in str(e.value)
    with pytest.raises(ExperimentError, match="seed-1/clean/untrained/all"):
        prepare.check_run_folder(tmp_path, work, ("seed-2/clean/day/all",), SCENES, 3, [1])
    prepare.check_run_folder(tmp_path, work, ("seed-1/clean/day/all",), SCENES, 3, [1])
    plan = prepare.Plan(folds={"splits": SPLITS}, mixes={}, new=False)
    prepare.write_setup(tmp_path, {"seed": 0, "seeds": 2}, plan, ("seed-1/clean/day/all",))
    assert not bad.parent.exists()
    assert (tmp_path / "units" / "clean" / "day" / "all" / "scores.json").is_file()
    assert (tmp_path / "seeds" / "1" / "units" / "clean" / "untrained" / "all").is_dir()


def test_a_fold_of_one_scene_gives_too_few_scenes_and_no_verdict_in_the_table(tmp_path):
    # fold 0 tests one scene: the per-fold row (and its comparisons) has no interval and no
    # verdict; the rows tested on all 5 scenes keep theirs
    splits = [{"fold": 0, "train": ["s2", "s3"], "val": ["s4"], "test": ["s0"]},
              {"fold": 1, "train": ["s0"], "val": ["s1"], "test": ["s1", "s2", "s3", "s4"]}]
    global SPLITS
    saved, SPLITS = SPLITS, splits
    try:
        _run_folder(tmp_path, [0], ["day", "mix5"])
    finally:
        SPLITS = saved
    t = table.build(_config([0], ["day", "mix5"]), tmp_path, splits, 5, 4)
    json.dumps(t, allow_nan=False)
    day, mix5 = t["rows"][1:]
    assert day["scores"]["clean"]["psnr"]["ci_low"] is not None
    s = mix5["scores"]["clean"]["psnr"]
    assert (s["ci_low"], s["ci_high"], s["note"]) == (None, None, stats.TOO_FEW)
    assert mix5["gain"]["clean"]["psnr"]["note"] == stats.TOO_FEW
    comps = [c for c in t["comparisons"] if c["row"] == "mix5"]
    assert comps and all(c["verdict"] is None and c["ci_low"] is None for c in comps)
    md = table.markdown(t)
    assert "(too few scenes for an interval)" in md and "| no verdict |" in md
    assert "[30.00, 30.00]" not in md
