"""read_dng matches LibRaw; render and the metrics match the command line."""

import json

import numpy as np
import OpenEXR
import pytest
import rawpy

import day2night

FIXTURE_NAMES = ["day.dng", "rggb_16bit_le_strips.dng", "bggr_14bit_packed_le_subifd_black2x2.dng",
                 "grbg_16bit_be_ljpeg_subifd.dng", "gbrg_10bit_packed_le_tiles.dng",
                 "rggb_12bit_ljpeg_tiles_deltas.dng"]


@pytest.mark.parametrize("name", FIXTURE_NAMES)
def test_read_dng_equals_libraw(name):
    from conftest import FIXTURES
    path = FIXTURES / name
    raw = day2night.read_dng(path)
    with rawpy.imread(str(path)) as r:
        assert np.array_equal(raw.data, r.raw_image)
        assert raw.meta["white_level"] == r.white_level
    assert raw.data.dtype == np.uint16 and not raw.data.flags.writeable
    assert raw.name == path.stem and raw.file_name == path.name
    m = raw.meta
    for k in ["cfa_pattern", "black_level", "white_level", "as_shot_neutral", "iso",
              "noise_profile", "active_area", "default_crop"]:
        assert k in m
    assert len(m["active_area"]) == 4 and len(m["default_crop"]) == 4


def test_real_file_meta(real_dng):
    raw = day2night.read_dng(real_dng)
    with rawpy.imread(str(real_dng)) as r:
        assert np.array_equal(raw.data, r.raw_image)
        assert raw.meta["cfa_pattern"] == "".join("RGBG"[c] for c in r.raw_pattern.flatten())
    assert "Raw(" in repr(raw)


def exr_rgb(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)


def test_render_and_metrics_match_cli(tmp_path, cli, real_dng):
    raw = day2night.read_dng(real_dng)
    cli("render", real_dng, "-o", tmp_path / "a.exr")
    rgb = day2night.render(raw)
    assert np.array_equal(rgb.astype(np.float16), exr_rgb(tmp_path / "a.exr").astype(np.float16))
    cli("render", real_dng, "-o", tmp_path / "b.exr", "--demosaic", "bilinear")
    a, b = exr_rgb(tmp_path / "a.exr"), exr_rgb(tmp_path / "b.exr")
    r = json.loads(cli("eval", tmp_path / "b.exr", tmp_path / "a.exr", "--json").stdout)
    assert day2night.psnr(b, a) == pytest.approx(r["psnr"], rel=1e-12)
    assert day2night.ssim(b, a) == pytest.approx(r["ssim"], rel=1e-12)
    assert day2night.delta_e2000(b, a) == pytest.approx(r["delta_e_2000"], rel=1e-12)
    assert day2night.ssim(b, a, window="gaussian") != day2night.ssim(b, a)
    assert day2night.psnr(a, a) == float("inf")
