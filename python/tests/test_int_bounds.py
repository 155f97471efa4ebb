"""Integer arguments: each has the range the command line accepts (src/bounds.rs,
``day2night.BOUNDS``); a value past it, negative or beyond any machine integer is a
``ValueError`` naming the argument and the range (never ``OverflowError``), and a value
that is not an integer is a ``TypeError`` naming it. Each argument is tried at its bound and
one past it, and the command line is tried at the same values where it has the flag."""

import re

import numpy as np
import pytest

import day2night

U64 = 2**64 - 1
U32 = 2**32 - 1
ISO_MAX = 4_000_000
LIGHTS_MAX = 256
JOBS_MAX = 4096
SMALL = dict(crop=(0, 0, 16, 16), isos=(1600,), target=None)


def outside(label, value, lo, hi):
    return re.escape(f"{label}: {value} is outside {lo}..={hi}")


@pytest.fixture(scope="module")
def raw():
    from conftest import FIXTURES
    return day2night.read_dng(FIXTURES / "day.dng")


def test_the_table():
    assert day2night.BOUNDS == {
        "seed": (0, U64), "variant": (0, U32 - 1), "variants": (1, U32),
        "iso": (1, ISO_MAX), "bulbs": (0, LIGHTS_MAX), "lights": (0, LIGHTS_MAX),
        "exr_zip_level": (1, 9), "threads": (0, JOBS_MAX), "val": (0, U64),
    }
    for key, (lo, hi) in day2night.BOUNDS.items():
        assert day2night.check_int(key, lo) == lo and day2night.check_int(key, hi) == hi
        with pytest.raises(ValueError, match=outside(key, hi + 1, lo, hi)):
            day2night.check_int(key, hi + 1)
        with pytest.raises(ValueError, match=outside(key, lo - 1, lo, hi)):
            day2night.check_int(key, lo - 1)
    with pytest.raises(ValueError, match="unknown argument"):
        day2night.check_int("seeds", 1)


@pytest.mark.parametrize("value", [-1, U64 + 1, -(2**200), 10**60])
def test_seed_past_its_bounds(raw, value):
    shown = str(value) if len(str(value)) <= 40 else str(value)[:20]
    with pytest.raises(ValueError, match=r"^seed: " + re.escape(shown) + r".* is outside 0\.\.=18446744073709551615"):
        day2night.synthesize(raw, seed=value, **SMALL)


def test_seed_at_its_bounds_and_the_cli(raw, cli, tmp_path):
    for s in (0, U64, np.uint64(U64)):
        assert day2night.synthesize(raw, seed=s, **SMALL)["plan"]["seed"] == int(s)
    # The CLI: the same plan at the top seed; one past it refused.
    cli("synth", raw.path, "-o", tmp_path / "a", "--seed", U64, "--iso", "none", "--target", "none")
    r = cli("synth", raw.path, "-o", tmp_path / "b", "--seed", U64 + 1, check=False)
    assert r.returncode == 2 and "--seed" in r.stderr
    with pytest.raises(TypeError, match="seed must be an integer"):
        day2night.synthesize(raw, seed=1.5, **SMALL)


def test_variant(raw):
    out = day2night.synthesize(raw, variant=U32 - 1, **SMALL)
    assert out["plan"]["variant"] == U32 - 1
    for v in (U32, -1):
        with pytest.raises(ValueError, match=outside("variant", v, 0, U32 - 1)):
            day2night.synthesize(raw, variant=v, **SMALL)


def test_isos(raw, cli, tmp_path):
    out = day2night.synthesize(raw, **{**SMALL, "isos": (1, ISO_MAX)})
    assert sorted(out["noisy"]) == [1, ISO_MAX]
    for bad, k in [((1600, ISO_MAX + 1), 1), ((0,), 0), ((-5,), 0), ((2**70,), 0)]:
        with pytest.raises(ValueError, match=outside(f"isos[{k}]", bad[k], 1, ISO_MAX)):
            day2night.synthesize(raw, **{**SMALL, "isos": bad})
    with pytest.raises(TypeError, match="isos must be a sequence"):
        day2night.synthesize(raw, **{**SMALL, "isos": "1600"})
    cli("synth", raw.path, "-o", tmp_path / "a", "--iso", ISO_MAX, "--target", "none")
    r = cli("synth", raw.path, "-o", tmp_path / "b", "--iso", ISO_MAX + 1, check=False)
    assert r.returncode != 0 and f"ISO {ISO_MAX + 1} is outside 1..={ISO_MAX}" in r.stderr


@pytest.mark.parametrize("name,flag", [("bulbs", "--bulbs"), ("lights", "--lights")])
def test_lights_and_bulbs(raw, cli, tmp_path, name, flag):
    assert day2night.synthesize(raw, **{**SMALL, name: LIGHTS_MAX})["plan"]
    for v in (LIGHTS_MAX + 1, -1):
        with pytest.raises(ValueError, match=outside(name, v, 0, LIGHTS_MAX)):
            day2night.synthesize(raw, **{**SMALL, name: v})
    cli("synth", raw.path, "-o", tmp_path / "a", flag, LIGHTS_MAX, "--iso", "none",
        "--target", "none")
    r = cli("synth", raw.path, "-o", tmp_path / "b", flag, LIGHTS_MAX + 1, check=False)
    assert r.returncode != 0 and f"{flag}: {LIGHTS_MAX + 1} is outside 0..={LIGHTS_MAX}" in r.stderr


def test_crop(raw):
    a = raw.meta["active_area"]
    ah, aw = a[2] - a[0], a[3] - a[1]
    top_max, left_max = (ah - 1) & ~1, (aw - 1) & ~1
    # At the bounds: the whole area, and the last even row and column.
    assert day2night.synthesize(raw, **{**SMALL, "crop": (0, 0, ah, aw)})["clean"].shape == (ah, aw)
    assert day2night.synthesize(raw, **{**SMALL, "crop": (top_max, left_max, ah - top_max,
                                                           aw - left_max)})["clean"].shape == (
        ah - top_max, aw - left_max)
    for crop, label, lo, hi in [
        ((top_max + 2, 0, 1, 8), "crop[0] (top)", 0, top_max),
        ((-2, 0, 8, 8), "crop[0] (top)", 0, top_max),
        ((0, left_max + 2, 8, 1), "crop[1] (left)", 0, left_max),
        ((0, -2, 8, 8), "crop[1] (left)", 0, left_max),
        ((0, 0, ah + 1, 8), "crop[2] (height)", 1, ah),
        ((4, 0, ah - 3, 8), "crop[2] (height)", 1, ah - 4),
        ((0, 0, -8, 8), "crop[2] (height)", 1, ah),
        ((0, 0, 8, aw + 1), "crop[3] (width)", 1, aw),
        ((0, 0, 8, 0), "crop[3] (width)", 1, aw),
        ((0, 0, 8, 2**64), "crop[3] (width)", 1, aw),
    ]:
        v = crop[int(label[5])]
        with pytest.raises(ValueError, match=outside(label, v, lo, hi)):
            day2night.synthesize(raw, **{**SMALL, "crop": crop})
    with pytest.raises(ValueError, match="even"):
        day2night.synthesize(raw, **{**SMALL, "crop": (1, 0, 8, 8)})
    with pytest.raises(ValueError, match="got 3 values"):
        day2night.synthesize(raw, **{**SMALL, "crop": (0, 0, 8)})


def test_night_pair_and_night_pairs(raw, day_dir):
    from day2night._native import night_pair
    assert night_pair(raw, U64, U32 - 1, ISO_MAX, (0, 0, 16, 16))["noisy"].shape == (4, 8, 8)
    for kw, msg in [({"seed": -1}, outside("seed", -1, 0, U64)),
                    ({"variant": U32}, outside("variant", U32, 0, U32 - 1)),
                    ({"iso": 0}, outside("iso", 0, 1, ISO_MAX)),
                    ({"crop": (0, 0, 16, 10**6)}, r"crop\[3\] \(width\)")]:
        args = {"seed": 0, "variant": 0, "iso": 1600, "crop": (0, 0, 16, 16), **kw}
        with pytest.raises(ValueError, match=msg):
            night_pair(raw, args["seed"], args["variant"], args["iso"], args["crop"])
    assert day2night.NightPairs(day_dir, crop=16, seed=U64, isos=(ISO_MAX,))[0]["iso"] == ISO_MAX
    with pytest.raises(ValueError, match=outside("seed", -1, 0, U64)):
        day2night.NightPairs(day_dir, crop=16, seed=-1)
    with pytest.raises(ValueError, match=outside("isos[1]", ISO_MAX + 1, 1, ISO_MAX)):
        day2night.NightPairs(day_dir, crop=16, isos=(1600, ISO_MAX + 1))


def test_threads(cli, day_dng, tmp_path):
    try:
        day2night.set_threads(JOBS_MAX)  # accepted (no pool is built until a computation)
        for v in (JOBS_MAX + 1, -1, 2**64):
            with pytest.raises(ValueError, match=outside("n", v, 0, JOBS_MAX)):
                day2night.set_threads(v)
    finally:
        day2night.set_threads(0)
    assert day2night.threads() >= 1
    # --jobs has the same upper bound (the bound itself is checked in src/bounds.rs's tests:
    # starting 4096 threads takes tens of seconds on a 2-core machine).
    for cmd in (["synth", day_dng, "-o", tmp_path / "s"], ["dataset", tmp_path, "-o", tmp_path / "d"]):
        r = cli(*cmd, "--jobs", JOBS_MAX + 1, check=False)
        assert r.returncode == 2 and f"--jobs: {JOBS_MAX + 1} is outside 1..={JOBS_MAX}" in r.stderr
        r = cli(*cmd, "--jobs", 0, check=False)
        assert r.returncode == 2 and f"--jobs: 0 is outside 1..={JOBS_MAX}" in r.stderr


def test_dataset_arguments(day_dir, tmp_path, cli):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=outside("variants", U32 + 1, 1, U32)):
        day2night.dataset_units(day_dir, out, variants=U32 + 1)
    with pytest.raises(ValueError, match=outside("variants", 0, 1, U32)):
        day2night.dataset_units(day_dir, out, variants=0)
    r = cli("dataset", day_dir, "-o", tmp_path / "c", "--variants", U32 + 1, check=False)
    assert r.returncode == 2
    for v in (-1, U64 + 1):
        with pytest.raises(ValueError, match=outside("val", v, 0, U64)):
            day2night.dataset_units(day_dir, out, val=v)
        with pytest.raises(ValueError, match=outside("seed", v, 0, U64)):
            day2night.dataset_units(day_dir, out, seed=v)
    # At the bounds: the seed is the stream key; val larger than the inputs is refused later.
    units = day2night.dataset_units(day_dir, out, seed=U64, val=2, variants=2)
    assert [u["seed"] for u in units] == [U64] * 4 and {u["split"] for u in units} == {"val"}
    with pytest.raises(ValueError, match="val"):
        day2night.dataset_units(day_dir, out, val=U64)
    # write_unit's options and the unit's own fields.
    u = units[0]
    with pytest.raises(ValueError, match=outside("exr_zip_level", 10, 1, 9)):
        day2night.write_unit(u, out, exr_zip_level=10)
    with pytest.raises(ValueError, match=outside("exr_zip_level", 0, 1, 9)):
        day2night.write_unit(u, out, exr_zip_level=0)
    for k, v in [("bulbs", LIGHTS_MAX + 1), ("lights", -1)]:
        with pytest.raises(ValueError, match=outside(k, v, 0, LIGHTS_MAX)):
            day2night.write_unit(u, out, **{k: v})
    with pytest.raises(ValueError, match=outside("iso", ISO_MAX + 1, 1, ISO_MAX)):
        day2night.write_unit(u, out, iso=ISO_MAX + 1)
    with pytest.raises(ValueError, match=outside("iso[1]", -3, 1, ISO_MAX)):
        day2night.write_unit(u, out, iso=[800, -3])
    with pytest.raises(ValueError, match=re.escape('unit["variant"]: 3 is outside 1..=2')):
        day2night.write_unit({**u, "variant": 3, "id": None}, out)
    with pytest.raises(ValueError, match=re.escape('unit["seed"]: -1 is outside')):
        day2night.write_unit({**u, "seed": -1}, out)
    rec = day2night.write_unit(u, out, iso=[ISO_MAX], exr_zip_level=9, bulbs=LIGHTS_MAX,
                               lights=LIGHTS_MAX, target="exr")
    assert rec["status"] == "ok" and rec["iso"] == [ISO_MAX]
    r = cli("dataset", day_dir, "-o", tmp_path / "c", "--exr-zip-level", 10, check=False)
    assert r.returncode == 2 and "1..=9" in r.stderr
