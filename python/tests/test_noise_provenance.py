"""Where the noise model comes from (issue 24 points 2-3): synthesize returns the provenance
(also in its plan report) and raises the plan's warnings as UserWarning, as `day2night synth`
prints them; the estimate from the image is used when the input has no NoiseProfile."""

import warnings

import numpy as np

import day2night
from conftest import FIXTURES


def noisy_frame(iso, make="Canon", model="EOS 5D", seed=3):
    """A 14-bit 512x512 RGGB frame with smooth content and known noise var = a y + b."""
    rng = np.random.default_rng(seed)
    h = w = 512
    black, white = 1024, 16383
    yy, xx = np.mgrid[0:h, 0:w]
    y = 0.03 + 0.9 * (xx / w) * (0.8 + 0.2 * yy / h)
    a, b = 1e-4, 1e-6
    scale = white - black
    x = black + y * scale + np.sqrt(a * y + b) * scale * rng.standard_normal((h, w))
    data = np.clip(np.round(x), 0, white).astype(np.uint16)
    meta = {"cfa_pattern": "RGGB", "black_level": black, "white_level": white,
            "color_matrix1": np.eye(3), "calibration_illuminant1": 21,
            "as_shot_neutral": (1.0, 1.0, 1.0), "iso": iso, "noise_profile": None,
            "make": make, "model": model}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return day2night.Raw.from_array(data, meta, name="frame")


def synth(raw):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = day2night.synthesize(raw, seed=1, mode="day", isos=(1600,), target=None)
    noise = [str(w.message) for w in rec
             if issubclass(w.category, UserWarning) and "noise:" in str(w.message)]
    return out, noise


def test_estimate_is_used_and_recorded():
    out, noise = synth(noisy_frame(100))
    assert noise == []
    p = out["noise_provenance"]
    assert p == out["plan_report"]["noise_provenance"]
    assert p["source"] == "image_estimate"
    assert p["camera"]["make"] == "Canon" and p["camera"]["model"] == "EOS 5D"
    # S at ISO 1600 is the ISO-100 estimate x16: near 16 * 1e-4 per plane.
    for s, _ in out["noise_profile"][1600]:
        assert abs(s / 1.6e-3 - 1) < 0.1, s


def test_unknown_iso_warns_and_names_the_embedded_table():
    out, noise = synth(noisy_frame(None))
    assert out["noise_provenance"]["source"] == "embedded_s20fe"
    assert len(noise) == 1, noise
    msg = noise[0]
    assert msg.startswith("frame.dng: noise: the input has no NoiseProfile and its ISO is unknown")
    assert "another camera's noise, not Canon EOS 5D's" in msg
    assert "day2night calibrate noise --from-image" in msg


def test_paper_phone_keeps_its_table_without_a_warning():
    out, noise = synth(noisy_frame(100, make="samsung", model="SM-G780F"))
    assert noise == []
    assert out["noise_provenance"]["source"] == "embedded_s20fe"
    assert out["noise_provenance"]["camera"]["make"] == "samsung"


def test_noise_profile_file():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    out, noise = synth(raw)
    assert noise == []
    assert out["noise_provenance"]["source"] == "noise_profile"
    assert out["noise_provenance"]["camera"]["unique_camera_model"] == "day2night Fixture Camera"
