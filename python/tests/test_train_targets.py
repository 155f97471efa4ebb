"""day2night.train.targets: the linear target turned into the bytes of the command line's
8-bit sRGB PNG targets (`synth --target png`, `render -o x.png`)."""

import numpy as np
import pytest

import day2night
from day2night.train import targets


def read_png(path):
    skio = pytest.importorskip("skimage.io")
    return np.asarray(skio.imread(path))


def test_synth_png_target_bytes(tmp_path, cli, day_dng):
    raw = day2night.read_dng(day_dng)
    cli("synth", day_dng, "-o", tmp_path, "--seed", "3", "--iso", "1600", "--target", "png")
    png = read_png(tmp_path / f"{day_dng.stem}_target.png")
    out = day2night.synthesize(raw, seed=3, isos=(1600,))
    got = targets.srgb8(out["target"])
    assert got.dtype == np.uint8 and got.shape == png.shape
    assert np.array_equal(got, png)


def test_render_png_bytes_and_tones(tmp_path, cli, day_dng):
    raw = day2night.read_dng(day_dng)
    for tone in ("srgb", "release"):
        cli("render", day_dng, "-o", tmp_path / f"{tone}.png", "--tone", tone)
        png = read_png(tmp_path / f"{tone}.png")
        assert np.array_equal(targets.srgb8(day2night.render(raw), tone=tone), png)


def test_planar_input_and_the_aligned_target(day_dng):
    raw = day2night.read_dng(day_dng)
    lin = day2night.render(raw, crop=False, orient=False)
    a = targets.srgb8(lin)
    assert np.array_equal(targets.srgb8(np.ascontiguousarray(lin.transpose(2, 0, 1))), a)
    assert np.array_equal(targets.render_target(raw), a)
    from day2night.train import preprocess
    assert preprocess.network_input(raw).shape == a.shape
    # the quantizer: clamp, sRGB OETF, * 255 + 0.5 truncated
    v = np.array([[[-1.0, 0.0, 0.0031308], [0.5, 1.0, 7.0]]], dtype=np.float32)
    srgb = np.where(v <= 0.0031308, 12.92 * np.clip(v, 0, 1),
                    1.055 * np.clip(v, 0, 1) ** (1 / 2.4) - 0.055)
    assert np.array_equal(targets.srgb8(v), (srgb * 255 + 0.5).astype(np.uint8))
    with pytest.raises(ValueError, match="tone"):
        targets.srgb8(v, tone="filmic")
