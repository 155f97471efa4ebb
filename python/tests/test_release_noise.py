"""The release's noise (``--noise release``) is the extension's (src/noise/release.rs,
NumPy's legacy MT19937 and polar normal reimplemented bit for bit): the same bytes as the
numpy implementation the experiment had (release_noise_oracle.py), and the generator left
in the same state; its S20 FE table is the embedded calibration's, the one copy."""

import json
import pathlib

import numpy as np
import pytest

import release_noise_oracle as oracle

import day2night
from day2night import _native
from day2night.experiment import release_noise

ROOT = pathlib.Path(__file__).resolve().parents[2]


def same(plane, iso, seed):
    """Both implementations from generators in the same state: equal bytes, equal states."""
    a, b = np.random.RandomState(seed), np.random.RandomState(seed)
    ours = release_noise.add_release_noise(plane, iso, a)
    want = oracle.add_release_noise(plane, iso, b)
    assert ours.dtype == want.dtype == np.uint16 and ours.shape == want.shape
    assert np.array_equal(ours, want), (iso, np.flatnonzero(ours != want)[:5])
    sa, sb = a.get_state(), b.get_state()
    assert np.array_equal(sa[1], sb[1]) and sa[2:] == sb[2:]
    return ours


def test_the_table_is_the_embedded_one_and_the_oracles():
    assert release_noise.DN_TABLE == oracle.DN_TABLE
    dn = json.loads((ROOT / "calibration" / "samsung-s20fe" / "noise.json").read_text())
    dn = dn["dn_table"]
    t = _native.RELEASE_NOISE_TABLE
    assert (t["black"], t["white"]) == (dn["black"], dn["white"]) == (64.0, 1023.0)
    assert [list(r) for r in t["rows"]] == dn["rows"]


def test_the_experiments_cases_give_the_oracles_bytes():
    n = 1024
    plane = np.full((n, n), 500, np.uint16)
    plane[:, n // 2:] = 1020
    same(plane, 1600, release_noise.noise_key(0, "day.dng", 1600))
    same(np.full((4, 4), 4000, np.uint16), 3200, 1)
    stored = np.full((12, 10), 300, np.uint16)
    for key in (9, release_noise.noise_key(3, "x.dng", 3200)):
        ours = release_noise.release_noisy_plane(stored, [2, 4, 12, 10], 3200, key)
        assert np.array_equal(ours, oracle.release_noisy_plane(stored, [2, 4, 12, 10], 3200,
                                                               key))


@pytest.mark.parametrize("iso", sorted(oracle.DN_TABLE))
def test_every_iso_odd_sizes_dark_and_bright(iso):
    rng = np.random.default_rng(iso)
    # dark samples (negative variance: 0), the whole range, past the clip; odd sizes leave
    # a cached normal draw in the generator
    plane = rng.integers(0, 1100, (37, 51)).astype(np.uint16)
    plane[:3] = rng.integers(0, 70, (3, 51))
    same(plane, iso, iso)
    same(plane.astype(np.float64) + 0.25, iso, iso + 1)  # other dtypes: as float32
    gen = np.random.RandomState(5)
    gen.standard_normal(3)  # a generator with a cached draw, mid-key
    a, b = np.random.RandomState(), np.random.RandomState()
    a.set_state(gen.get_state())
    b.set_state(gen.get_state())
    ours = release_noise.add_release_noise(plane, iso, a)
    assert np.array_equal(ours, oracle.add_release_noise(plane, iso, b))


def test_a_synthesized_clean_raw_gives_the_oracles_bytes(day_dng):
    day = day2night.read_dng(str(day_dng))
    clean = day2night.synthesize(day, seed=0, isos=(), target=None)["clean"]
    area = day.meta.get("active_area") or [0, 0, *clean.shape]
    for iso in (1600, 3200):
        key = release_noise.noise_key(0, day.name, iso)
        ours = release_noise.release_noisy_plane(clean, area, iso, key)
        assert np.array_equal(ours, oracle.release_noisy_plane(clean, area, iso, key))


def test_refusals():
    with pytest.raises(ValueError, match="ISO 6400: the release's S20 FE table has 100, 200"):
        release_noise.add_release_noise(np.zeros((2, 2)), 6400, np.random.RandomState(0))
    with pytest.raises(ValueError, match="2-D"):
        release_noise.add_release_noise(np.zeros(4), 1600, np.random.RandomState(0))
    key = np.zeros(3, np.uint32)
    with pytest.raises(ValueError, match="624 key words"):
        _native.release_noise(np.zeros((2, 2), np.float32), 1600, (key, 0, 0, 0.0))
    with pytest.raises(ValueError, match="ISO 50: the release's S20 FE table has"):
        _native.release_noise(np.zeros((2, 2), np.float32), 50,
                              (np.zeros(624, np.uint32), 624, 0, 0.0))
