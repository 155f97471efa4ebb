"""Folds and mixes of the experiment (issue 31 item 2), on index lists without images:
the paper's 105 scenes in 3 folds are 60/10/35, the test folds are disjoint and cover every
scene, 5 % and 10 % of 60 training slots are exactly 3 and 6 real scenes, and bad requests
are clear errors."""

import json
import math

import numpy as np
import pytest

from day2night.experiment import folds, mix

SCENES = [f"{i:03d}" for i in range(1, 106)]


def test_105_scenes_in_3_folds_are_60_10_35_disjoint_and_covering():
    m = folds.make_folds(SCENES, 3, seed=7)
    assert m["folds"] == 3 and m["scenes"] == SCENES
    tested = []
    for s in m["splits"]:
        assert (len(s["train"]), len(s["val"]), len(s["test"])) == (60, 10, 35)
        tr, va, te = set(s["train"]), set(s["val"]), set(s["test"])
        assert not (tr & va) and not (tr & te) and not (va & te)
        assert tr | va | te == set(SCENES)
        for lst in (s["train"], s["val"], s["test"]):
            assert lst == sorted(lst)
        tested += s["test"]
    assert sorted(tested) == SCENES  # each scene tested exactly once


def test_folds_are_seeded():
    a = folds.make_folds(SCENES, 3, seed=1)
    assert a == folds.make_folds(list(reversed(SCENES)), 3, seed=1)  # input order is irrelevant
    b = folds.make_folds(SCENES, 3, seed=2)
    assert a["splits"][0]["test"] != b["splits"][0]["test"]


@pytest.mark.parametrize("n,k", [(3, 3), (4, 2), (10, 3), (11, 4), (106, 3)])
def test_uneven_and_small_sets_still_cover(n, k):
    ids = [f"s{i}" for i in range(n)]
    m = folds.make_folds(ids, k, seed=0)
    sizes = sorted(len(s["test"]) for s in m["splits"])
    assert sizes[-1] - sizes[0] <= 1 and sum(sizes) == n
    assert sorted(t for s in m["splits"] for t in s["test"]) == sorted(ids)
    assert all(s["train"] and s["val"] for s in m["splits"])


def test_manifest_round_trip_and_corruption(tmp_path):
    m = folds.make_folds(SCENES, 3, seed=0)
    p = tmp_path / "folds.json"
    folds.write_folds(p, m)
    assert folds.read_folds(p) == m
    assert not [f for f in tmp_path.iterdir() if f.name != "folds.json"]  # no temp file left
    bad = json.loads(p.read_text())
    bad["splits"][1]["test"].append(bad["splits"][0]["test"][0])
    p.write_text(json.dumps(bad))
    with pytest.raises(folds.FoldError, match=str(p)):
        folds.read_folds(p)
    p.write_text("{not json")
    with pytest.raises(folds.FoldError, match="cannot read"):
        folds.read_folds(p)


@pytest.mark.parametrize(
    "n,k,msg",
    [
        (2, 3, "3 folds need at least 3 scenes.*has 2"),
        (3, 2, "too small for 2 folds"),
        (5, 1, "at least 2 folds"),
        (0, 3, "has 0"),
    ],
)
def test_fold_errors(n, k, msg):
    with pytest.raises(folds.FoldError, match=msg):
        folds.make_folds([f"s{i}" for i in range(n)], k)


def test_duplicate_scene_is_named():
    with pytest.raises(folds.FoldError, match="s1"):
        folds.make_folds(["s0", "s1", "s1", "s2"], 2)


TRAIN = SCENES[:60]
SYNTH = [f"day{i:02d}.dng" for i in range(60)]


@pytest.mark.parametrize("percent,real", [(5, 3), (10, 6), (0, 0), (100, 60), (50, 30), (2.5, 2)])
def test_mix_counts_are_exact(percent, real):
    slots = mix.mix(TRAIN, SYNTH, percent)
    assert len(slots) == 60
    assert sum(s["kind"] == "real" for s in slots) == real
    assert mix.real_count(percent, 60) == real


def test_mix_follows_the_release_permutation_and_conventions():
    slots = mix.mix(TRAIN, SYNTH, 5, seed=101)
    replaced = set(int(i) for i in np.random.RandomState(101).permutation(60)[:57])
    for i, s in enumerate(slots):
        assert s["slot"] == i
        assert s["iso"] == (1600 if i % 2 == 0 else 3200)
        if i in replaced:
            assert (s["kind"], s["id"], s["wb"]) == ("synthetic", SYNTH[i], "avg_night")
        else:
            assert (s["kind"], s["id"], s["wb"]) == ("real", TRAIN[i], "as_shot")
    assert mix.mix(TRAIN, SYNTH, 5, seed=101) == slots
    other = mix.mix(TRAIN, SYNTH, 5, seed=3)
    assert [s["id"] for s in other if s["kind"] == "real"] != [
        s["id"] for s in slots if s["kind"] == "real"
    ]


def test_mix_reuses_synthetic_items_when_fewer():
    slots = mix.mix(TRAIN[:5], ["a.dng", "b.dng"], 0)
    assert [s["id"] for s in slots] == ["a.dng", "b.dng", "a.dng", "b.dng", "a.dng"]


@pytest.mark.parametrize("bad", [-1, 100.5, 101, math.nan, "5", None, True])
def test_mix_percentage_outside_0_100_is_refused(bad):
    with pytest.raises(mix.MixError, match="percentage"):
        mix.mix(TRAIN, SYNTH, bad)


def test_mix_needs_synthetic_items():
    with pytest.raises(mix.MixError, match="synthetic"):
        mix.mix(TRAIN, [], 5)
    assert len(mix.mix(TRAIN, [], 100)) == 60  # supervised needs none


def test_day_images_split_like_the_release():
    names = [f"d{i:02d}.dng" for i in range(70)]
    train, val = mix.split_day_images(reversed(names))
    assert train == names[:60] and val == names[60:]
    assert mix.split_day_images(["a", "b", "c"]) == (["a", "b"], ["c"])
    with pytest.raises(mix.MixError, match="at least 2"):
        mix.split_day_images(["a"])
