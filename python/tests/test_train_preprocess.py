"""day2night.train.preprocess: the network input equals the authors' release's, whose steps
(pipeline/pipeline_utils.py: normalize, white_balance, demosaic with alg_type '', then
test.py's ** (1 / 2.2)) are written out here with numpy and OpenCV."""

import os

import numpy as np
import pytest

import day2night
from day2night.train import preprocess

# The release's OpenCV flags for RGB output (get_opencv_demsaic_flag): OpenCV names a
# Bayer pattern by the 2x2 block at (1, 1), so RGGB is BAYER_BG.
FLAGS = {"RGGB": "COLOR_BAYER_BG2RGB", "BGGR": "COLOR_BAYER_RG2RGB",
         "GRBG": "COLOR_BAYER_GB2RGB", "GBRG": "COLOR_BAYER_GR2RGB"}


def cv2():
    try:
        import cv2 as m
    except ImportError as e:
        if os.environ.get("D2N_REQUIRE_VALIDATORS") == "1":
            pytest.fail(f"D2N_REQUIRE_VALIDATORS=1 but OpenCV cannot be imported: {e}")
        pytest.skip(f"opencv-python-headless is not installed ({e}); "
                    "tests/validators/requirements.txt has it")
    return m


def release_input(plane, meta, neutral):
    """The release's input of a visible raw, step by step."""
    cv = cv2()
    x = plane.astype(np.float32)
    black = [float(b) for b in meta["black_level"]]
    rr, rc = meta["black_level_repeat_dim"]
    mask = np.zeros_like(x)
    for i in range(2):
        for j in range(2):
            mask[i::2, j::2] = black[(i % rr) * rc + j % rc] if len(black) > 1 else black[0]
    norm = x - mask
    norm[norm < 0] = 0
    norm = norm / (float(meta["white_level"]) - mask)
    cfa = ["RGB".index(c) for c in meta["cfa_pattern"]]
    wb = np.zeros(norm.shape)
    for k, (i, j) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1)]):
        wb[i::2, j::2] = norm[i::2, j::2] / neutral[cfa[k]]
    wb = np.clip(wb, 0.0, 1.0)
    q = (wb * 16383).astype(np.uint16)
    rgb = cv.cvtColor(q, getattr(cv, FLAGS[meta["cfa_pattern"]])).astype(np.float32) / 16383
    return rgb ** (1 / 2.2)


def active(raw):
    t, l, b, r = raw.meta["active_area"]
    return raw.data[t:b, l:r]


def check_against_release(raw, neutral=None):
    n = neutral if neutral is not None else raw.meta["as_shot_neutral"]
    want = release_input(active(raw), raw.meta, n)
    got = preprocess.network_input(raw, neutral=neutral)
    assert got.dtype == np.float32 and got.shape == want.shape
    d = np.abs(got - want).max()
    assert d <= 1 / 255, f"max difference {d}"
    return got, want


def test_fixture_input_matches_the_release(day_dng):
    raw = day2night.read_dng(day_dng)
    got, want = check_against_release(raw)
    # in fact the same numbers (same quantization, same integer demosaic)
    assert np.abs(got - want).max() < 1e-6


def test_real_camera_input_matches_the_release(real_dng):
    raw = day2night.read_dng(real_dng)
    check_against_release(raw)


@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_every_bayer_phase_matches_opencv(pattern):
    cv = cv2()
    rng = np.random.default_rng(1)
    m = rng.integers(0, 16384, (23, 30)).astype(np.uint16)
    want = cv.cvtColor(m, getattr(cv, FLAGS[pattern]))
    assert np.array_equal(preprocess.demosaic_bilinear(m, pattern), want)


def test_given_neutral_and_gamma_switch(day_dng):
    raw = day2night.read_dng(day_dng)
    night = (0.7, 1.0, 0.4)
    check_against_release(raw, neutral=night)
    lin = preprocess.network_input(raw, neutral=night, gamma=None)
    g = preprocess.network_input(raw, neutral=night)
    assert np.allclose(lin ** np.float32(1 / 2.2), g, atol=1e-6)


def test_array_input_and_crops(day_dng):
    raw = day2night.read_dng(day_dng)
    same = day2night.Raw.from_array(raw.data, raw.meta, name=raw.name)
    full = preprocess.network_input(raw)
    assert np.array_equal(preprocess.network_input(same), full)
    # an even-offset crop: its inside equals the whole image's (the border row/column of a
    # crop copies its neighbour, as OpenCV does at an image edge)
    plane = active(raw)[10:74, 20:100]
    c = preprocess.network_input_array(plane, raw.meta, raw.meta["as_shot_neutral"], 10, 20)
    assert np.array_equal(c[1:-1, 1:-1], full[11:73, 21:99])
    # an odd offset moves the CFA phase and is followed
    plane = active(raw)[11:75, 21:101]
    c = preprocess.network_input_array(plane, raw.meta, raw.meta["as_shot_neutral"], 11, 21)
    assert np.array_equal(c[1:-1, 1:-1], full[12:74, 22:100])


def test_bad_input_is_refused(day_dng):
    raw = day2night.read_dng(day_dng)
    with pytest.raises(ValueError, match="neutral"):
        preprocess.network_input(raw, neutral=(1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="Bayer"):
        preprocess.demosaic_bilinear(np.zeros((8, 8), np.uint16), "RRGB")
    with pytest.raises(ValueError, match="3x3"):
        preprocess.demosaic_bilinear(np.zeros((2, 8), np.uint16), "RGGB")
    meta = dict(raw.meta, as_shot_neutral=None)
    with pytest.raises(ValueError, match="AsShotNeutral"):
        preprocess.network_input_array(active(raw), meta)
