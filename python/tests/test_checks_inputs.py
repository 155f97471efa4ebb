"""Input checks that used to disagree between entry points (issue 30, "Checks that
disagree"), on Python's side: colour matrices that map white to no light, an invalid
NoiseProfile, a negative noise model parameter and an unknown CalibrationIlluminant give the
refusal or warning `info`, `synth` and `render` give (tests/it/checks_inputs.rs)."""

import json
import warnings

import numpy as np
import pytest

import day2night

FM = np.array([[0.6, 0.3, 0.1], [0.25, 0.7, 0.05], [0.0, 0.1, 0.75]])


def frame(**meta):
    yy, xx = np.mgrid[0:48, 0:64]
    data = (256 + (0.2 + 0.6 * xx / 64) * 3000 + 10 * yy).astype(np.uint16)
    m = {"cfa_pattern": "RGGB", "black_level": 256, "white_level": 4095,
         "color_matrix1": np.eye(3), "calibration_illuminant1": 21,
         "as_shot_neutral": (0.5, 1.0, 0.6), "iso": 100, "noise_profile": [(2e-5, 4e-7)]}
    m.update(meta)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        raw = day2night.Raw.from_array(data, m, name="frame")
    return raw, [str(w.message) for w in rec]


def run(raw, **opts):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = day2night.synthesize(raw, seed=1, mode="day", isos=(1600,), **opts)
    return out, [str(w.message) for w in rec]


@pytest.mark.parametrize("fm", [np.zeros((3, 3)), -FM])
def test_a_forward_matrix_mapping_white_to_no_light_is_refused_for_a_render(fm):
    good, _ = frame(forward_matrix1=FM)
    run(good)
    raw, _ = frame(forward_matrix1=fm)
    with pytest.raises(ValueError) as e:
        run(raw)
    assert "non-positive luminance" in str(e.value), str(e.value)
    assert "--target none" in str(e.value), str(e.value)
    # Without a render the matrices are not used.
    run(raw, target=None)


def test_an_invalid_noise_profile_is_reported_as_invalid():
    raw, read = frame(noise_profile=[(-1e-4, 1e-6)])
    assert any("NoiseProfile pair 0 (S -1e-4, O 1e-6)" in w for w in read), read
    out, msgs = run(raw, target=None)
    said = " ".join(msgs) + json.dumps(out["noise_provenance"])
    assert "invalid NoiseProfile pair 0 (S -1e-4, O 1e-6)" in said, said
    assert "has no NoiseProfile" not in said, said


def test_a_negative_noise_model_parameter_is_warned_about(tmp_path):
    model = tmp_path / "neg.json"
    model.write_text(json.dumps({
        "format": "day2night-noise-model/1", "units": "normalized", "source": "test",
        "isos": [{"iso": 1600, "positions": [[1e-4, -1], [1e-4, 1e-6], [1e-4, 1e-6],
                                             [1e-4, 1e-6]]}]}))
    raw, _ = frame()
    _, msgs = run(raw, target=None, noise_model=str(model))
    hit = [m for m in msgs if "negative parameters" in m]
    assert hit and "ISO 1600 position 0 (S 1e-4, O -1)" in hit[0], msgs
    assert "clamps them to 0" in hit[0], hit


def test_a_calibration_illuminant_outside_the_exif_table_is_warned_about():
    _, read = frame(calibration_illuminant1=99)
    assert any("CalibrationIlluminant1 99 is not an EXIF LightSource code" in w
               for w in read), read
    _, read = frame()
    assert not any("CalibrationIlluminant" in w for w in read), read
