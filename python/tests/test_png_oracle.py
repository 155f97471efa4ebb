"""The extension's PNG writer (``day2night.png_bytes``: src/encode/png_rows.rs, the file
``day2night render -o x.png`` writes) and the numpy/zlib oracle (png_oracle.py, the
package's former encoder) decode to the same samples, the input's: odd and even sizes, one
row or column, more rows than one compressed group, RGB and grey, strided views (the eight
orientations of an image); other dtypes and shapes are refused."""

import io

import numpy as np
import pytest
from PIL import Image

import png_oracle

import day2night
from day2night import png

SHAPES = [(1, 1), (1, 7), (5, 1), (7, 5), (64, 33), (97, 130)]


def images(h, w):
    rng = np.random.default_rng(h * 1000 + w)
    noise = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    ramp = np.add.outer(np.arange(h), np.arange(w))[:, :, None] * np.array([1, 2, 3])
    return noise, (ramp % 256).astype(np.uint8)


def decoded(data, tmp_path):
    """The samples of PNG bytes, by the package's reader and by Pillow (both must agree)."""
    f = tmp_path / "x.png"
    f.write_bytes(data)
    ours = png.read_png(f)
    assert np.array_equal(ours, np.asarray(Image.open(io.BytesIO(data)).convert("RGB")))
    return ours


@pytest.mark.parametrize("shape", SHAPES)
def test_extension_and_oracle_decode_to_the_input(shape, tmp_path):
    for a in images(*shape):
        for grey in (False, True):
            x = a[:, :, 1] if grey else a
            want = np.repeat(x[:, :, None], 3, 2) if grey else x
            got = decoded(day2night.png_bytes(x), tmp_path)
            assert np.array_equal(got, want), (shape, grey)
            assert np.array_equal(decoded(png_oracle.png_bytes(x), tmp_path), got)


def test_every_orientation_view_is_written_as_it_reads(tmp_path):
    noise, _ = images(37, 53)
    views = [noise, noise[::-1], noise[:, ::-1], noise[::-1, ::-1]]
    views += [v.transpose(1, 0, 2) for v in views]
    for v in views:
        assert np.array_equal(decoded(day2night.png_bytes(v), tmp_path), v)
        assert np.array_equal(decoded(png_oracle.png_bytes(v), tmp_path), v)


def test_colour_chunks_and_the_writer(tmp_path):
    a = images(40, 50)[1]
    chunks = {t: day2night.png_bytes(a, tone=t) for t in ("srgb", "gamma22", "release")}
    assert b"sRGB" in chunks["srgb"] and b"gAMA" in chunks["gamma22"]
    assert b"sRGB" not in chunks["release"] and b"gAMA" not in chunks["release"]
    png.write_png(tmp_path / "w.png", a)
    assert (tmp_path / "w.png").read_bytes() == chunks["srgb"]


def test_other_arrays_are_refused():
    for bad in (np.zeros((4, 4, 3), np.float32), np.zeros((4, 4, 3), np.uint16),
                np.zeros((4, 4, 4), np.uint8), np.zeros(4, np.uint8)):
        with pytest.raises(ValueError, match="uint8 \\(H, W\\) or \\(H, W, 3\\) array"):
            day2night.png_bytes(bad)
    with pytest.raises(ValueError):
        day2night.png_bytes(np.zeros((0, 4, 3), np.uint8))
