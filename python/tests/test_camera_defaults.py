"""Every camera its own night in Python (issue 24 point 5): the same per-camera defaults as
`day2night synth` (the paper phone's gray cards for the S20 FE, the CIE lamps through the
file's own colour matrices for every other camera), `illuminants="paper" | "cie" | path`,
the provenance in the result, and NightPairs items made with each file's own defaults."""

import json
import warnings

import numpy as np

import day2night
from day2night import NightPairs

# An off-diagonal XYZ -> camera matrix, as a small-sensor module has.
CM = np.array([[0.9, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.1, 0.3, 0.6]])


def frame(make, model, name):
    """A 12-bit 64x64 RGGB frame with smooth content."""
    yy, xx = np.mgrid[0:64, 0:64]
    data = (256 + (0.1 + 0.8 * xx / 64 * (0.7 + 0.3 * yy / 64)) * 3500).astype(np.uint16)
    meta = {"cfa_pattern": "RGGB", "black_level": 256, "white_level": 4095,
            "color_matrix1": CM, "calibration_illuminant1": 21,
            "as_shot_neutral": (0.5, 1.0, 0.6), "iso": 100,
            "noise_profile": [(2e-5, 4e-7)], "make": make, "model": model}
    return day2night.Raw.from_array(data, meta, name=name)


def run(raw, **opts):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        out = day2night.synthesize(raw, seed=3, mode="global", isos=(1600,), target=None,
                                   **opts)
    ill = [str(w.message) for w in rec
           if issubclass(w.category, UserWarning) and "night illuminants" in str(w.message)]
    return out, ill


def test_each_camera_gets_its_own_default_and_says_so():
    other = frame("Canon", "EOS 5D", "canon")
    out, warned = run(other)
    p = out["illuminants_provenance"]
    assert p["source"] == "cie_lamps", p
    assert p["camera"]["make"] == "Canon" and p["camera"]["model"] == "EOS 5D"
    assert warned == []
    phone = frame("samsung", "SM-G781B", "phone")
    out_p, warned_p = run(phone)
    assert out_p["illuminants_provenance"]["source"] == "embedded_s20fe"
    assert warned_p == []
    # The two cameras' lights differ: the same stream, other dictionaries.
    assert out["neutral"] != out_p["neutral"]


def test_explicit_choices_and_the_release_preset():
    other = frame("Canon", "EOS 5D", "canon")
    out, warned = run(other, illuminants="paper")
    assert out["illuminants_provenance"]["source"] == "embedded_s20fe"
    # Another camera's neutrals applied to this camera: a warning naming both.
    assert len(warned) == 1 and "EOS 5D" in warned[0] and "S20 FE" in warned[0], warned
    out_r, warned_r = run(other, compat="release")
    assert out_r["illuminants_provenance"]["source"] == "embedded_s20fe"
    assert out_r["neutral"] == out["neutral"]
    assert len(warned_r) == 1
    out_c, warned_c = run(frame("samsung", "SM-G780F", "phone"), illuminants="cie")
    assert out_c["illuminants_provenance"]["source"] == "cie_lamps"
    assert warned_c == []


def test_an_xy_file_is_converted_through_the_cameras_matrices(tmp_path):
    f = tmp_path / "lamps.json"
    f.write_text(json.dumps({"lamps": [{"name": "HP1", "weight": 3},
                                       {"name": "porch", "xy": [0.46, 0.41]}]}))
    out, warned = run(frame("Canon", "EOS 5D", "canon"), illuminants=str(f))
    p = out["illuminants_provenance"]
    assert p["source"] == "file_xy" and p["file"].endswith("lamps.json"), p
    assert warned == []


def test_night_pairs_items_use_each_files_own_camera(tmp_path):
    d = tmp_path / "days"
    d.mkdir()
    day2night.write_dng(frame("Canon", "EOS 5D", "canon"), d / "a.dng")
    day2night.write_dng(frame("samsung", "SM-G781B", "phone"), d / "b.dng")
    ds = NightPairs(d, crop=16, isos=(1600,), seed=5, crops_per_image=2)
    sources = set()
    for i in range(len(ds)):
        it = ds[i]
        raw = day2night.read_dng(d / f"{it['name']}.dng")
        top, left = (int(v) for v in it["origin"])
        p = ds.params(i)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = day2night.synthesize(raw, seed=5, variant=p["variant"], isos=(it["iso"],),
                                       crop=(top, left, 16, 16))
        sources.add((it["name"], out["illuminants_provenance"]["source"]))
        assert np.array_equal(
            day2night.pack_bayer(out["noisy"][it["iso"]], raw.meta, top, left), it["noisy"])
        assert np.array_equal(out["target"].transpose(2, 0, 1), it["target"])
    assert sources == {("a", "cie_lamps"), ("b", "embedded_s20fe")}
