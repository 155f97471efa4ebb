"""The extension's PNG decoder (``day2night.png_decode``: the ``image`` crate) reads what
the project writes, as the package's former numpy decoder (png_read_oracle.py) read it:
``day2night.png_bytes`` files of many shapes, the command line's render; 16-bit grey and
RGB come back as uint16; hostile files (not a PNG, truncated, corrupt, huge dimensions)
give one-line errors naming the file, refused on the header before anything is inflated."""

import struct
import zlib

import numpy as np
import pytest
from PIL import Image

import png_oracle
import png_read_oracle

import day2night
from day2night import png

SHAPES = [(1, 1), (1, 7), (5, 1), (7, 5), (64, 33), (97, 130)]


def images(h, w):
    rng = np.random.default_rng(h * 1000 + w)
    noise = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    ramp = np.add.outer(np.arange(h), np.arange(w))[:, :, None] * np.array([1, 2, 3])
    return noise, (ramp % 256).astype(np.uint8)


def both(path):
    """The package's read_png and the oracle's, which must agree."""
    ours = png.read_png(path)
    assert ours.dtype == np.uint8 and ours.flags.c_contiguous
    assert np.array_equal(ours, png_read_oracle.read_png(path))
    assert png.check_png(path) == png_read_oracle.check_png(path) == ours.shape[:2]
    return ours


@pytest.mark.parametrize("shape", SHAPES)
def test_written_pngs_decode_as_the_oracle_decodes_them(shape, tmp_path):
    f = tmp_path / "x.png"
    for a in images(*shape):
        for grey in (False, True):
            x = a[:, :, 1] if grey else a
            data = day2night.png_bytes(x, tone="gamma22")
            raw = day2night.png_decode(data)
            assert raw.dtype == np.uint8 and raw.shape == (*shape, 3)
            f.write_bytes(data)
            want = np.repeat(x[:, :, None], 3, 2) if grey else x
            assert np.array_equal(both(f), want)
            assert np.array_equal(raw, want)


def test_other_writers_filters_and_channels(tmp_path):
    """Pillow's optimizer picks Sub/Up/Average/Paeth filters per row; grey, RGBA, grey +
    alpha and palette files read as Pillow converts them to RGB."""
    a = images(45, 61)[0]
    for mode in ("RGB", "RGBA", "L", "LA", "P"):
        f = tmp_path / f"{mode}.png"
        Image.fromarray(a).convert(mode).save(f, optimize=True)
        want = np.asarray(Image.open(f).convert("RGB"))
        assert np.array_equal(png.read_png(f), want), mode
        if mode in ("RGB", "RGBA", "L"):
            assert np.array_equal(png_read_oracle.read_png(f), want), mode
    raw = day2night.png_decode((tmp_path / "LA.png").read_bytes())
    assert raw.shape == (45, 61, 2)


def test_render_png_decodes_as_the_oracle_decodes_it(tmp_path, cli, day_dng):
    out = tmp_path / "t.png"
    cli("render", day_dng, "-o", out)
    y = both(out)
    assert y.ndim == 3 and y.shape[2] == 3 and y.std() > 0


@pytest.mark.parametrize("shape", [(1, 1), (7, 5), (64, 33), (40, 30, 3)])
def test_sixteen_bit_round_trip(shape, tmp_path):
    rng = np.random.default_rng(sum(shape))
    a = rng.integers(0, 65536, shape, dtype=np.uint16)
    got = day2night.png_decode(png_oracle.png16_bytes(a))
    assert got.dtype == np.uint16
    assert np.array_equal(got, a.reshape(*shape[:2], -1))
    f = tmp_path / "x16.png"
    f.write_bytes(png_oracle.png16_bytes(a))
    with pytest.raises(png.PngError, match=r"x16.png: only 8-bit PNGs are read \(this one has "
                                           r"16-bit samples\)"):
        png.read_png(f)
    if a.ndim == 2:  # Pillow writes 16-bit grey too (mode I;16)
        Image.fromarray(a).save(f)
        assert np.array_equal(day2night.png_decode(f.read_bytes())[:, :, 0], a)


def chunk(tag, body):
    crc = zlib.crc32(tag + body) & 0xFFFFFFFF
    return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", crc)


def header_only(w, h, depth=8, colour=2):
    """A PNG whose header claims w x h, with one small IDAT (a decompression bomb's
    shape: the work is the header's, the file is tiny)."""
    head = struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0)
    return (png_oracle.SIGNATURE + chunk(b"IHDR", head)
            + chunk(b"IDAT", zlib.compress(b"\0" * 4096)) + chunk(b"IEND", b""))


def one_line_error(path, data, match):
    path.write_bytes(data)
    with pytest.raises(png.PngError) as e:
        png.read_png(path)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"{path}: "), msg
    assert match in msg, msg
    with pytest.raises(png.PngError):
        png.check_png(path)
    return msg


def test_hostile_pngs_give_one_line_errors(tmp_path):
    f = tmp_path / "bad.png"
    good = day2night.png_bytes(images(50, 40)[0])
    one_line_error(f, b"not a png", "not a PNG file")
    one_line_error(f, good[:8], "not a readable PNG")
    one_line_error(f, good[: len(good) // 2], "not a readable PNG")
    one_line_error(f, good[:-12], "not a readable PNG")  # no IEND
    bad_crc = bytearray(good)
    bad_crc[29] ^= 0xFF  # inside IHDR's CRC
    one_line_error(f, bytes(bad_crc), "not a readable PNG")
    one_line_error(f, header_only(100_000, 4), "100000x4 is larger than 65535 a side")
    one_line_error(f, header_only(60_000, 60_000), "60000")  # over D2N_MAX_PIXELS
    one_line_error(f, header_only(0, 5), "not a readable PNG")
    # inside the limits but its rows missing: an error, not a black image
    one_line_error(f, header_only(2000, 2000), "not a readable PNG")
    with pytest.raises(png.PngError, match="missing.png: cannot read"):
        png.read_png(tmp_path / "missing.png")
    with pytest.raises(ValueError, match="^PNG: "):
        day2night.png_decode(b"\x89PNG\r\n\x1a\n")
