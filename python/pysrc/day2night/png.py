"""8-bit PNG reading and writing, both by the extension: ``day2night.png_bytes`` encodes (the
library's PNG writer, src/encode/png_rows.rs), ``day2night.png_decode`` decodes (the
``image`` crate's decoder, the one ``day2night real-pairs`` reads PNGs with), its work
bounded by the file's header (python/src/png_decode.rs).

Reads 8-bit greyscale, RGB or RGBA (with or without a palette, any filter, interlaced or
not). Writes 8-bit RGB (a greyscale array as R = G = B) through a temporary file + rename."""

import numpy as np

from ._native import png_bytes, png_decode
from .atomic import write_bytes

__all__ = ["PngError", "png_bytes", "write_png", "read_png", "check_png"]

SIGNATURE = b"\x89PNG\r\n\x1a\n"


class PngError(ValueError):
    """A PNG this reader cannot read (the message names the file)."""


def write_png(path, array):
    """An 8-bit (H, W, 3) or (H, W) array as a PNG, written atomically."""
    write_bytes(path, png_bytes(array))


def read_png(path):
    """An 8-bit PNG as uint8 (H, W, 3) (greyscale is repeated, alpha dropped)."""
    img = _decode(path)
    if img.shape[2] <= 2:
        return np.ascontiguousarray(np.repeat(img[:, :, :1], 3, axis=2))
    return np.ascontiguousarray(img[:, :, :3])


def check_png(path):
    """(H, W) of a PNG :func:`read_png` reads, decoded in full (every chunk and row
    checked): PngError otherwise."""
    h, w, _ = _decode(path).shape
    return h, w


def _decode(path):
    """The samples (uint8, H x W x C) of an 8-bit PNG file, else PngError naming it."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise PngError(f"{path}: cannot read: {e.strerror or e}") from None
    if not data.startswith(SIGNATURE):
        raise PngError(f"{path}: not a PNG file")
    try:
        img = png_decode(data)
    except ValueError as e:
        raise PngError(f"{path}: {str(e).removeprefix('PNG: ')}") from None
    if img.dtype != np.uint8:
        raise PngError(f"{path}: only 8-bit PNGs are read (this one has "
                       f"{8 * img.dtype.itemsize}-bit samples)")
    return img
