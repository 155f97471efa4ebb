"""The extension's network input (``day2night.release_codes``, ``demosaic_bilinear``:
src/isp/release_input.rs) equals the numpy oracle (release_input_oracle.py, the package's
former formulation) code for code: every Bayer phase, odd and even sizes and offsets, a
BlackLevel pattern, a LinearizationTable, strided planes; and other dtypes are refused."""

import numpy as np
import pytest

import release_input_oracle as oracle

import day2night
from day2night.train import preprocess

PATTERNS = ["RGGB", "BGGR", "GRBG", "GBRG"]
SIZES = [(3, 3), (4, 5), (23, 30), (31, 17)]


def meta(pattern, black=(60, 64.5, 66, 70), white=1023, table=None):
    return {"cfa_pattern": pattern, "black_level": list(black),
            "black_level_repeat_dim": [2, 2] if len(black) == 4 else [1, 1],
            "white_level": white, "linearization_table": table,
            "as_shot_neutral": [0.6, 1.0, 0.3]}


def plane(h, w, seed, hi=1100):
    return np.random.default_rng(seed).integers(0, hi, (h, w)).astype(np.uint16)


@pytest.mark.parametrize("pattern", PATTERNS)
@pytest.mark.parametrize("size", SIZES)
def test_codes_equal_the_oracle_for_every_phase_size_and_offset(pattern, size):
    p = plane(*size, seed=sum(size))
    m = meta(pattern)
    for top, left in [(0, 0), (1, 0), (0, 1), (3, 5)]:
        for neutral in (None, (0.7, 1.0, 0.4), np.array([1.2, 0.9, 2.0])):
            got = day2night.release_codes(p, m, neutral, top, left)
            want = oracle.release_codes(p, m, neutral, top, left)
            assert got.dtype == np.uint16 and got.shape == (*size, 3)
            assert np.array_equal(got, want), (pattern, size, top, left, neutral)


def test_linearization_one_black_level_and_strided_planes():
    curve = np.minimum(np.arange(1200) * 7 / 8 + np.arange(1200) ** 2 / 4000, 4095)
    m = meta("GRBG", black=(64,), white=4095, table=list(curve.astype(int)))
    p = plane(40, 36, seed=3, hi=1500)  # samples past the table's end take its last entry
    assert np.array_equal(day2night.release_codes(p, m), oracle.release_codes(p, m))
    # views: flipped, transposed, every other column (the CFA is the view's own)
    for view in (p[::-1], p.T, p[:, ::2], p[3:30:3, 1:]):
        assert np.array_equal(day2night.release_codes(view, m), oracle.release_codes(view, m))


@pytest.mark.parametrize("pattern", PATTERNS + [[0, 1, 1, 2], [[1, 2], [0, 1]]])
def test_demosaic_equals_the_oracle_on_14_and_16_bit_codes(pattern):
    name = pattern if isinstance(pattern, str) else "".join(
        "RGB"[c] for c in np.ravel(pattern))
    for h, w in SIZES + [(64, 65)]:
        for hi in (16384, 65536):  # 16-bit codes: the sums must not overflow
            m = np.random.default_rng(h * w).integers(0, hi, (h, w)).astype(np.uint16)
            got = day2night.demosaic_bilinear(m, pattern)
            assert np.array_equal(got, oracle.demosaic_bilinear(m, name)), (name, h, w, hi)


def test_network_input_of_the_fixture_is_the_oracle_through_the_table(day_dng):
    raw = day2night.read_dng(day_dng)
    plane = preprocess.active_plane(raw)
    for gamma in (preprocess.GAMMA, None):
        got = preprocess.network_input(raw, gamma=gamma)
        want = preprocess._table(gamma)[oracle.release_codes(plane, raw.meta)]
        assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


def test_other_dtypes_and_bad_arguments_are_refused():
    m = meta("RGGB")
    for dtype in (np.uint8, np.int32, np.float32):
        with pytest.raises(ValueError, match=f"2-D uint16 array \\(got dtype {np.dtype(dtype)}"):
            day2night.release_codes(np.zeros((8, 8), dtype), m)
        with pytest.raises(ValueError, match="mosaic must be a 2-D uint16"):
            day2night.demosaic_bilinear(np.zeros((8, 8), dtype), "RGGB")
    p = np.zeros((8, 8), np.uint16)
    with pytest.raises(ValueError, match="3x3"):
        day2night.demosaic_bilinear(np.zeros((2, 8), np.uint16), "RGGB")
    with pytest.raises(ValueError, match="Bayer"):
        day2night.demosaic_bilinear(p, "RRGB")
    with pytest.raises(ValueError, match="neutral"):
        day2night.release_codes(p, m, (1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="neutral"):
        day2night.release_codes(p, m, (1.0, 1.0))
    with pytest.raises(ValueError, match="AsShotNeutral"):
        day2night.release_codes(p, dict(m, as_shot_neutral=None))
    with pytest.raises(ValueError, match="no cfa_pattern"):
        day2night.release_codes(p, dict(m, cfa_pattern=None))
    with pytest.raises(ValueError, match="white level"):
        day2night.release_codes(p, dict(m, white_level=50))
