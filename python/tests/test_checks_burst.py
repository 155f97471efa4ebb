"""Checks that used to disagree between the command line and Python (issue 30, "Checks that
disagree"): the burst options follow the command line's rules with its messages in Python's
spelling, a shake step too large for the image is refused with its size, frames with little
valid area are warned about, and bad metadata in Raw.from_array blames the right key. The
command line's side is tests/it/checks_burst.rs and tests/it/checks_inputs.rs."""

import warnings

import numpy as np
import pytest

import day2night


@pytest.fixture(scope="module")
def raw(day_dng):
    return day2night.read_dng(day_dng)


def small(w=64, h=48, **meta):
    yy, xx = np.mgrid[0:h, 0:w]
    data = (256 + (0.2 + 0.6 * xx / w) * 3000 + 10 * yy).astype(np.uint16)
    m = {"cfa_pattern": "RGGB", "black_level": 256, "white_level": 4095,
         "color_matrix1": np.eye(3), "calibration_illuminant1": 21,
         "as_shot_neutral": (0.5, 1.0, 0.6), "iso": 100, "noise_profile": [(2e-5, 4e-7)]}
    m.update(meta)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return day2night.Raw.from_array(data, m, name="small")


def synth(raw, **opts):
    return day2night.synthesize(raw, seed=1, isos=(1600,), target=None, **opts)


@pytest.mark.parametrize("opts, exc, words", [
    (dict(burst=1, motion="none"), ValueError, "motion needs a burst (burst N with N > 1)"),
    (dict(shake_step=2.0), ValueError, "shake_step needs a burst"),
    (dict(burst=3, motion="none", shake_step=5.0), ValueError,
     "shake_step has no effect with motion none"),
    (dict(burst=-1), ValueError, "burst: -1 is outside 1..=64"),
    (dict(burst=65), ValueError, "burst: 65 is outside 1..=64"),
    (dict(burst=10 ** 40), ValueError, "burst: "),
    (dict(burst=True), TypeError, "burst must be an integer (got bool)"),
    (dict(burst=2.0), TypeError, "burst must be an integer"),
    (dict(burst=3, shake_step=1e308), ValueError, "shake_step: 1e308 is outside 0..=1000"),
    (dict(burst=3, shake_step="2"), TypeError, "shake_step must be a number"),
    (dict(burst=3, shake_roll=float("nan")), ValueError, "shake_roll: NaN is not a finite number"),
    (dict(burst=3, motion="tripod"), ValueError, 'motion: "tripod" (use none or shake)'),
])
def test_burst_options_follow_the_command_line_rules(raw, opts, exc, words):
    with pytest.raises(exc) as e:
        synth(raw, **opts)
    assert words in str(e.value), str(e.value)
    assert len(str(e.value)) < 400, str(e.value)


def test_the_same_rules_as_the_command_line(cli, day_dng, tmp_path):
    """Each pair: the command line refuses iff Python refuses."""
    raw = day2night.read_dng(day_dng)
    for i, (flags, kwargs) in enumerate([
        (["--burst", "1", "--motion", "shake"], dict(burst=1, motion="shake")),
        (["--shake-step", "2"], dict(shake_step=2.0)),
        (["--burst", "3", "--motion", "none", "--shake-step", "5"],
         dict(burst=3, motion="none", shake_step=5.0)),
        (["--burst", "2", "--motion", "none"], dict(burst=2, motion="none")),
    ]):
        # a folder per case: an accepted case writes its outputs
        r = cli("synth", day_dng, "-o", tmp_path / f"o{i}", "--iso", "1600", "--target", "none",
                *flags, check=False)
        try:
            synth(raw, **kwargs)
            py_ok = True
        except ValueError:
            py_ok = False
        assert (r.returncode == 0) == py_ok, (flags, r.stderr)


def test_a_shake_step_too_large_for_the_image_is_refused_with_its_size():
    with pytest.raises(ValueError) as e:
        synth(small(), burst=3, shake_step=1000.0)
    assert "too large for the 64x48 active area" in str(e.value), str(e.value)
    with pytest.raises(ValueError) as e:
        synth(small(), burst=3, shake_step=50.0)
    assert "50 px is too large for the 64x48 active area (at most 12 px" in str(e.value)


def test_frames_with_little_valid_area_are_warned_about():
    warned = 0
    for seed in (1, 2, 3, 4):
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            out = day2night.synthesize(small(), seed=seed, isos=(1600,), target=None,
                                       burst=16, shake_step=12.0)
        msgs = [str(w.message) for w in rec if "valid area under half" in str(w.message)]
        little = [t["frame"] for t in out["transforms"]
                  if t["valid"]["width"] * t["valid"]["height"] < 0.5 * 64 * 48]
        assert bool(msgs) == bool(little), (seed, msgs, little)
        if msgs:
            warned += 1
            assert f"{len(little)} of 16 frames" in msgs[0], msgs[0]
            for f in little:
                assert f"f{f:02d} " in msgs[0], (f, msgs[0])
    assert warned, "no seed gave a frame with little valid area"


@pytest.mark.parametrize("meta, keys", [
    (dict(black_level=5000), ['meta["black_level"]', 'meta["white_level"]']),
    (dict(white_level=0, black_level=0), ['meta["black_level"]', 'meta["white_level"]']),
])
def test_a_black_level_above_white_blames_the_levels(meta, keys):
    with pytest.raises(ValueError) as e:
        small(**meta)
    msg = str(e.value)
    for k in keys:
        assert k in msg, msg
    assert "black_level_delta" not in msg, msg
