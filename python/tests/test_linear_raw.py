"""LinearRaw DNGs (already demosaiced, three samples per pixel) in Python: ``read_dng`` gives
a ``Raw`` whose ``data`` is height x width x 3, ``render`` equals ``day2night render``'s EXR
values, and the synthesis refuses them with the reason the command line gives.

Files: the shared LG G4 file (lossy JPEG LinearRaw in a SubIFD, with an OpcodeList2) and the
LinearRaw files tests/validators/make_compressed_dngs.py writes with tifffile + imagecodecs
(lossless and lossy JPEG XL, lossy JPEG; per-sample black and white levels)."""

import os
import subprocess
import sys

import numpy as np
import OpenEXR
import pytest

import day2night
from conftest import ROOT, shared_file

REASON = "LinearRaw: already demosaiced; the night synthesis works on the CFA mosaic"
GENERATED = ["linear_jxl_tiles", "linear_jxl_lossy", "linear_jpeg_tiles"]
NAMES = ["lg_g4"] + GENERATED


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    try:
        import imagecodecs  # noqa: F401
    except ImportError as e:
        if os.environ.get("D2N_REQUIRE_VALIDATORS") == "1":
            pytest.fail(f"D2N_REQUIRE_VALIDATORS=1 but imagecodecs is missing: {e}")
        pytest.skip(f"imagecodecs is not installed ({e}): tests/validators/requirements.txt")
    out = tmp_path_factory.mktemp("linear")
    script = ROOT / "tests" / "validators" / "make_compressed_dngs.py"
    r = subprocess.run([sys.executable, str(script), str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    return out


@pytest.fixture()
def linear(request, made):
    name = request.param
    if name == "lg_g4":
        return shared_file("dng-bad/lg_g4_linearraw_lossyjpeg_subifd.dng")
    return made / f"{name}.dng"


def exr_rgb(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)


@pytest.mark.parametrize("linear", NAMES, indirect=True)
def test_read_dng_gives_a_linear_raw(linear, made):
    raw = day2night.read_dng(linear)
    m = raw.meta
    h, w = m["height"], m["width"]
    assert raw.data.shape == (h, w, 3) and raw.data.dtype == np.uint16
    assert not raw.data.flags.writeable
    assert m["cfa_pattern"] is None and m["samples_per_pixel"] == 3
    rr, rc = m["black_level_repeat_dim"]
    assert len(m["black_level"]) == rr * rc * 3 and len(m["white_level"]) == 3
    assert "LinearRaw x3" in repr(raw)
    assert raw.path == str(linear) and raw.name == linear.stem
    if linear.parent == made:
        # The samples the generator wrote (lossless) or tifffile's decode (lossy: JPEG and
        # JPEG XL decoders may differ by a code or two).
        want = np.fromfile(made / f"{linear.stem}.bin", dtype="<u2").reshape(h, w, 3)
        diff = np.abs(raw.data.astype(np.int32) - want.astype(np.int32)).max()
        if linear.stem == "linear_jxl_tiles":
            assert diff == 0
            assert m["black_level"] == [100, 200, 300]
            assert m["white_level"] == [60000, 61000, 62000]
        else:
            assert diff <= 4, diff
    else:
        assert raw.data.shape == (338, 600, 3)
        assert m["make"] == "LG Mobile" and m["opcode_list2"] is not None
        assert m["white_level"] == [255, 255, 255]


@pytest.mark.parametrize("linear", NAMES, indirect=True)
@pytest.mark.parametrize("flags,kwargs", [
    ([], {}),
    (["--opcodes", "ignore"], {"opcodes": "ignore"}),
    (["--no-crop", "--no-orient"], {"crop": False, "orient": False}),
    (["--neutral", "0.5,1,0.7"], {"neutral": (0.5, 1, 0.7)}),
])
def test_render_equals_the_cli(linear, flags, kwargs, cli, tmp_path):
    raw = day2night.read_dng(linear)
    exr = tmp_path / "r.exr"
    cli("render", linear, "-o", exr, "--float", *flags)
    rgb = day2night.render(raw, **kwargs)
    ref = exr_rgb(exr)
    assert rgb.dtype == np.float32 and rgb.shape == ref.shape
    assert np.array_equal(rgb, ref)
    # The half-float EXR `render` writes by default holds the same values, rounded.
    cli("render", linear, "-o", tmp_path / "h.exr", *flags)
    assert np.array_equal(rgb.astype(np.float16), exr_rgb(tmp_path / "h.exr").astype(np.float16))


@pytest.mark.parametrize("linear", NAMES, indirect=True)
def test_synthesis_refuses_with_the_cli_reason(linear, cli, tmp_path):
    raw = day2night.read_dng(linear)
    r = cli("synth", linear, "-o", tmp_path / "night", check=False)
    assert r.returncode == 1 and REASON in r.stderr
    with pytest.raises(ValueError) as e:
        day2night.synthesize(raw)
    assert str(linear) in str(e.value) and REASON in str(e.value)
    assert str(e.value) in r.stderr  # the CLI prints "day2night: <same message>"
    with pytest.raises(ValueError, match=REASON):
        day2night.synthesize(raw, crop=(0, 0, 16, 16), isos=(1600,))
    # NightPairs items (one native call each) refuse it too.
    d = tmp_path / "days"
    d.mkdir()
    (d / "x.dng").write_bytes(linear.read_bytes())
    with pytest.raises(ValueError, match=REASON):
        day2night.NightPairs(d, crop=16)[0]
    # The dataset units read it with the CLI's reader: a failed record with the reason.
    units = day2night.dataset_units(d, tmp_path / "out")
    rec = day2night.write_unit(units[0], tmp_path / "out")
    assert rec["status"] == "failed" and REASON in rec["error"]
    # Nor does it become a CFA raw or a DNG.
    with pytest.raises(ValueError, match="2-D"):
        day2night.Raw.from_array(raw.data, raw.meta, name="x")
    with pytest.raises(ValueError, match="samples_per_pixel"):
        day2night.Raw.from_array(raw.data[..., 0], raw.meta, name="x")
    with pytest.raises(ValueError, match="LinearRaw"):
        day2night.write_dng(raw, tmp_path / "x.dng")
    assert not (tmp_path / "x.dng").exists()
