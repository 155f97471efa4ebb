"""Raws from any source: Raw.from_array (the invariant: a read DNG rebuilt from its
.data and .meta synthesizes, renders and writes the same), from_rawpy and write_dng (the
DNG SDK, rawpy, OpenImageIO, tifffile and exiftool accept what it writes)."""

import json
import subprocess
import sys
import warnings

import numpy as np
import pytest
import rawpy

import day2night
from conftest import FIXTURES, ROOT, require_tool, shared_file

# Fixtures synthesis accepts: strips and tiles, 10 to 16 bits, IFD0 and SubIFD, LJ92,
# a 2x2 black pattern, black deltas, a linearization table.
SYNTH_FIXTURES = ["day.dng", "rggb_16bit_le_strips.dng", "bggr_14bit_packed_le_subifd_black2x2.dng",
                  "grbg_16bit_be_ljpeg_subifd.dng", "gbrg_10bit_packed_le_tiles.dng",
                  "rggb_12bit_ljpeg_tiles_deltas.dng", "gbrg_10bit_linearization_be.dng"]
# Fixtures whose rawpy view is the file's own (no black deltas, no linearization table).
RAWPY_FIXTURES = SYNTH_FIXTURES[:5]
CANON = "dng/canon_kissx4_magiclantern_rggb14_strips.dng"


def rebuilt(raw):
    """Raw.from_array of a read raw's parts: no default may be needed (no warning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return day2night.Raw.from_array(raw.data, raw.meta, name=raw.name)


def assert_same_synthesis(a, b, **kw):
    x = day2night.synthesize(a, seed=5, variant=1, isos=(1600, 6400), **kw)
    y = day2night.synthesize(b, seed=5, variant=1, isos=(1600, 6400), **kw)
    assert np.array_equal(x["clean"], y["clean"])
    for iso in (1600, 6400):
        assert np.array_equal(x["noisy"][iso], y["noisy"][iso])
    assert np.array_equal(x["target"], y["target"])
    assert x["plan"] == y["plan"] and x["neutral"] == y["neutral"]
    assert x["noise_profile"] == y["noise_profile"]
    return x, y


@pytest.mark.parametrize("name", SYNTH_FIXTURES)
def test_from_array_of_a_read_dng_synthesizes_the_same(name):
    raw = day2night.read_dng(FIXTURES / name)
    again = rebuilt(raw)
    assert again.name == raw.name and again.file_name == raw.file_name
    assert again.path is None and raw.path is not None
    assert np.array_equal(again.data, raw.data)
    assert again.meta == raw.meta
    assert_same_synthesis(raw, again)
    assert_same_synthesis(raw, again, crop=(2, 4, 16, 22), mode="global")
    assert np.array_equal(day2night.render(raw), day2night.render(again))


def test_from_array_takes_any_strides():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    m = raw.meta
    want = day2night.synthesize(raw, seed=1, isos=(3200,))
    big = np.zeros((raw.data.shape[0] * 2, raw.data.shape[1] * 3), np.uint16)
    big[::2, ::3] = raw.data
    for data in (np.asfortranarray(raw.data), big[::2, ::3], raw.data.T.copy().T):
        r = day2night.Raw.from_array(data, m, name="day")
        got = day2night.synthesize(r, seed=1, isos=(3200,))
        assert np.array_equal(got["noisy"][3200], want["noisy"][3200])
        assert np.array_equal(got["target"], want["target"])


def test_from_array_writes_the_same_files(tmp_path, day_dng):
    """The EXR target is byte-identical; the DNGs hold the same pixels and modelled tags
    (tags the dict does not model, e.g. a file's XMP or private Exif entries, are not in
    it); the sidecar differs only in input.sha256 (there is no input file to hash)."""
    raw = day2night.read_dng(day_dng)
    again = rebuilt(raw)
    a, b = tmp_path / "a", tmp_path / "b"
    fa = day2night.write_outputs(day2night.synthesize(raw, seed=2, isos=(1600,)), raw, a)
    fb = day2night.write_outputs(day2night.synthesize(again, seed=2, isos=(1600,)), again, b)
    assert fa == fb
    for f in fa:
        if f.endswith(".exr"):
            assert (a / f).read_bytes() == (b / f).read_bytes(), f
        elif f.endswith(".dng"):
            x, y = day2night.read_dng(a / f), day2night.read_dng(b / f)
            assert np.array_equal(x.data, y.data), f
            assert x.meta == y.meta, f
        elif f.endswith(".json"):
            x, y = json.loads((a / f).read_text()), json.loads((b / f).read_text())
            assert x["input"].pop("sha256") != y["input"].pop("sha256")
            assert x == y


def test_missing_colour_metadata_gets_defaults_with_warnings():
    raw = day2night.read_dng(FIXTURES / "day.dng")
    m = {k: raw.meta[k] for k in ("cfa_pattern", "black_level", "white_level")}
    with pytest.warns(UserWarning) as rec:
        r = day2night.Raw.from_array(raw.data, m, name="bare")
    said = " | ".join(str(w.message) for w in rec)
    for key in ("color_matrix1", "as_shot_neutral", "iso", "noise_profile"):
        assert f"meta['{key}'] missing" in said or f'meta["{key}"] missing' in said, said
    assert "D65" in said and "bare.dng" in said
    meta = r.meta
    assert meta["calibration_illuminant1"] == 21 and meta["as_shot_white_xy"] == [0.3127, 0.329]
    assert meta["iso"] is None and meta["bits_per_sample"] == 12
    assert r.file_name == "bare.dng"
    out = day2night.synthesize(r, seed=0, isos=(1600,))
    assert np.isfinite(out["target"]).all()
    rgb = day2night.render(r)
    assert rgb.shape[2] == 3 and np.isfinite(rgb).all()
    # An explicit None means "absent, as in a DNG without the tag": no default, no warning.
    m2 = dict(m, color_matrix1=None, as_shot_neutral=[0.5, 1, 0.7], iso=None, noise_profile=None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r2 = day2night.Raw.from_array(raw.data, m2, name="bare")
    assert r2.meta["color_matrix1"] is None


def base_meta():
    return {"cfa_pattern": "RGGB", "black_level": 64, "white_level": 4095,
            "color_matrix1": np.eye(3), "calibration_illuminant1": 21,
            "as_shot_neutral": (0.5, 1.0, 0.6), "iso": 100, "noise_profile": None}


@pytest.mark.parametrize("change,match", [
    ({"white_level": None}, "white_level"),
    ({"cfa_pattern": "RGGX"}, "cfa_pattern"),
    ({"cfa_pattern": "RRGB"}, "cfa_pattern"),
    ({"cfa_pattern": [0, 1, 1]}, "cfa_pattern"),
    ({"black_level": 5000}, "black_level"),
    ({"black_level": [1, 2, 3]}, "black_level_repeat_dim"),
    ({"as_shot_neutral": (1, -1, 1)}, "as_shot_neutral"),
    ({"as_shot_neutral": (1, 1)}, "as_shot_neutral"),
    ({"color_matrix1": [1, 2, 3]}, "color_matrix1"),
    ({"color_matrix1": [float("nan")] * 9}, "color_matrix1"),
    ({"orientation": 9}, "orientation"),
    ({"iso": 0}, "iso"),
    ({"iso": "high"}, "iso"),
    ({"noise_profile": [1e-4, 1e-6, 3]}, "noise_profile"),
    ({"active_area": [0, 0, 100, 8]}, "ActiveArea"),
    ({"width": 9}, "width"),
    ({"bits_per_sample": 10}, "BitsPerSample"),
    ({"colour_matrix1": np.eye(3)}, "unknown key"),
])
def test_bad_metadata_is_a_valueerror_naming_the_key(change, match):
    m = base_meta()
    m.update(change)
    if change.get("white_level", 0) is None:
        del m["white_level"]
    data = np.full((6, 8), 2000, np.uint16)
    with pytest.raises(ValueError, match=match):
        day2night.Raw.from_array(data, m, name="x")


@pytest.mark.parametrize("data", [np.zeros((4, 4), np.float32), np.zeros((4, 4, 1), np.uint16),
                                  [[1, 2], [3, 4]]])
def test_bad_arrays_are_valueerrors(data):
    with pytest.raises(ValueError, match="uint16"):
        day2night.Raw.from_array(data, base_meta(), name="x")


def test_bad_names():
    for name in ("", "a/b", ".."):
        with pytest.raises(ValueError, match="name"):
            day2night.Raw.from_array(np.zeros((4, 4), np.uint16), base_meta(), name=name)
    r = day2night.Raw.from_array(np.zeros((4, 4), np.uint16), base_meta(), name="x.DNG")
    assert (r.name, r.file_name) == ("x", "x.DNG")


def dng_check(source, *outs):
    """tests/validators/dng_check.py: rawpy, the Adobe DNG SDK (dngpy), OpenImageIO and
    tifffile on OUT against SOURCE."""
    r = subprocess.run([sys.executable, str(ROOT / "tests/validators/dng_check.py"), str(source),
                        *map(str, outs)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def exiftool_warnings(exe, path):
    r = subprocess.run([exe, "-validate", "-warning", "-a", "-s3", str(path)],
                       capture_output=True, text=True)
    return {line.replace("SubIFD ", "IFD ").replace("IFD0 ", "IFD ")
            for line in r.stdout.splitlines() if line.startswith("[")}


def exiftool_validate(source, path):
    """`exiftool -validate` finds nothing in PATH it does not find in SOURCE (as
    tests/it/dng_roundtrip.rs); without exiftool the test fails or is skipped
    (conftest.require_tool)."""
    exe = require_tool("exiftool", "libimage-exiftool-perl")
    new = exiftool_warnings(exe, path) - exiftool_warnings(exe, source)
    assert not new, f"{path}: exiftool -validate warnings the source lacks: {sorted(new)}"


@pytest.mark.parametrize("name", SYNTH_FIXTURES)
def test_write_dng_of_a_read_or_rebuilt_raw(tmp_path, name):
    src = FIXTURES / name
    raw = day2night.read_dng(src)
    a, b, c = tmp_path / "read.dng", tmp_path / "rebuilt.dng", tmp_path / "lj92.dng"
    day2night.write_dng(raw, a)
    day2night.write_dng(rebuilt(raw), b)
    day2night.write_dng(rebuilt(raw), c, compression="ljpeg")
    for p in (a, b, c):
        back = day2night.read_dng(p)
        assert np.array_equal(back.data, raw.data)
        for k in ("cfa_pattern", "black_level", "white_level", "as_shot_neutral", "color_matrix1",
                  "active_area", "default_crop", "orientation", "iso", "noise_profile"):
            assert back.meta[k] == raw.meta[k], (p, k)
    if "linearization" not in name:
        dng_check(src, a, b, c)
    exiftool_validate(src, b)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["lj92.dng", "read.dng", "rebuilt.dng"]


def test_write_dng_refuses_to_overwrite_and_bad_options(tmp_path, day_dng):
    raw = day2night.read_dng(day_dng)
    p = tmp_path / "x.dng"
    p.write_bytes(b"keep")
    with pytest.raises(ValueError, match="overwrite"):  # as write_outputs
        day2night.write_dng(raw, p)
    assert p.read_bytes() == b"keep"
    day2night.write_dng(raw, p, overwrite=True)
    assert np.array_equal(day2night.read_dng(p).data, raw.data)
    with pytest.raises(ValueError, match="compression"):
        day2night.write_dng(raw, p, overwrite=True, compression="zip")
    with pytest.raises(ValueError, match="input"):
        day2night.write_dng(raw, day_dng, overwrite=True)  # never over its own input
    assert sorted(x.name for x in tmp_path.iterdir()) == ["x.dng"]


def check_from_rawpy(src, tmp_path):
    """from_rawpy of SOURCE equals day2night's own reading where LibRaw knows the value,
    synthesizes, and its DNG passes the validators against SOURCE."""
    raw = day2night.read_dng(src)
    with rawpy.imread(str(src)) as rp:
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            r = day2night.from_rawpy(rp, raw.name, make=raw.meta["make"], model=raw.meta["model"],
                                     noise_profile=raw.meta["noise_profile"], iso=raw.meta["iso"])
    said = [str(w.message) for w in rec]
    assert not any("color_matrix1" in s or "as_shot_neutral" in s for s in said), said
    m, want = r.meta, raw.meta
    assert np.array_equal(r.data, raw.data)
    for k in ("cfa_pattern", "active_area", "default_crop", "orientation", "make", "model"):
        assert m[k] == want[k], k
    assert m["white_level"] == want["white_level"]
    assert np.allclose(m["black_level"], want["black_level"]) or len(m["black_level"]) != len(want["black_level"])
    assert np.allclose(m["as_shot_neutral"], want["as_shot_neutral"], rtol=1e-6)
    assert np.allclose(m["color_matrix1"], want["color_matrix1"], rtol=1e-5, atol=1e-6)
    out = day2night.synthesize(r, seed=0, isos=(1600,), crop=(0, 0, 32, 32))
    assert out["noisy"][1600].shape == (32, 32)
    p = tmp_path / f"{src.stem}_rawpy.dng"
    day2night.write_dng(r, p)
    report = dng_check(src, p)
    exiftool_validate(src, p)
    return report


@pytest.mark.parametrize("name", RAWPY_FIXTURES)
def test_from_rawpy_fixtures(tmp_path, name):
    check_from_rawpy(FIXTURES / name, tmp_path)


def test_from_rawpy_real_canon(tmp_path):
    check_from_rawpy(shared_file(CANON), tmp_path)


def test_from_rawpy_is_duck_typed_and_refuses_non_bayer():
    class Sizes:
        raw_height, raw_width, height, width = 6, 8, 4, 6
        top_margin, left_margin, flip = 2, 2, 6
        crop_top_margin = crop_left_margin = crop_width = crop_height = 0

    class Fake:
        raw_type = 0
        color_desc = b"RGBG"
        sizes = Sizes()
        raw_image = np.arange(48, dtype=np.uint16).reshape(6, 8)
        raw_colors_visible = np.array([[1, 2], [0, 3]])
        black_level_per_channel = [10, 11, 12, 11]
        white_level = 1023
        camera_whitebalance = [2.0, 1.0, 1.5, 0.0]
        rgb_xyz_matrix = np.vstack([np.eye(3), np.zeros((1, 3))])

    with pytest.warns(UserWarning) as rec:
        r = day2night.from_rawpy(Fake(), "fake")
    said = " | ".join(str(w.message) for w in rec)
    assert "iso" in said and "noise_profile" in said and "color_matrix1" not in said
    m = r.meta
    assert m["cfa_pattern"] == "GBRG" and m["active_area"] == [2, 2, 6, 8]
    assert m["black_level"] == [11, 12, 10, 11] and m["black_level_repeat_dim"] == (2, 2)
    assert m["orientation"] == 6 and m["as_shot_neutral"] == [0.5, 1.0, 1 / 1.5]
    assert m["color_matrix1"] == list(np.eye(3).ravel()) and m["bits_per_sample"] == 10
    Fake.raw_type = 1
    with pytest.raises(ValueError, match="Bayer"):
        day2night.from_rawpy(Fake(), "fake")
    Fake.raw_type, Fake.color_desc = 0, b"CMYG"
    with pytest.raises(ValueError, match="RGB"):
        day2night.from_rawpy(Fake(), "fake")
