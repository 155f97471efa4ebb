"""The numpy/zlib PNG decoder the package had before it called the extension's
(``day2night.png_decode``: the ``image`` crate, python/src/png_decode.rs), kept as the
oracle of test_png_decode.py: 8-bit greyscale, RGB or RGBA, non-interlaced, any filter."""

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"
CHANNELS = {0: 1, 2: 3, 6: 4}


class PngError(ValueError):
    """A PNG this reader cannot read (the message names the file)."""


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def _unfilter(raw, h, stride, bpp, path):
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.int32)
    pos = 0
    for y in range(h):
        ft = raw[pos]
        line = np.frombuffer(raw, np.uint8, stride, pos + 1).astype(np.int32)
        pos += stride + 1
        if ft == 0:
            cur = line
        elif ft == 2:
            cur = (line + prev) & 0xFF
        elif ft in (1, 3, 4):
            cur = line.copy()
            for x in range(stride):
                a = cur[x - bpp] if x >= bpp else 0
                if ft == 1:
                    pred = a
                elif ft == 3:
                    pred = (a + prev[x]) >> 1
                else:
                    pred = _paeth(a, prev[x], prev[x - bpp] if x >= bpp else 0)
                cur[x] = (cur[x] + pred) & 0xFF
        else:
            raise PngError(f"{path}: row {y} has an unknown filter type {ft}")
        out[y] = cur
        prev = cur
    return out


def read_png(path):
    """An 8-bit PNG as uint8 (H, W, 3) (greyscale is repeated, alpha dropped)."""
    raw, h, w, c = _inflate(path)
    img = _unfilter(raw, h, w * c, c, path).reshape(h, w, c)
    if c == 1:
        return np.repeat(img, 3, axis=2)
    return np.ascontiguousarray(img[:, :, :3])


def check_png(path):
    """(H, W) of a PNG :func:`read_png` reads, checked without unfiltering its rows (the
    chunks, the inflated size and every row's filter type): PngError otherwise."""
    raw, h, w, c = _inflate(path)
    filters = np.frombuffer(raw, np.uint8)[:: w * c + 1]
    bad = np.flatnonzero(filters > 4)
    if bad.size:
        raise PngError(f"{path}: row {int(bad[0])} has an unknown filter type "
                       f"{int(filters[bad[0]])}")
    return h, w


def _inflate(path):
    """(inflated rows, H, W, channels) of an 8-bit non-interlaced PNG, else PngError."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise PngError(f"{path}: cannot read: {e.strerror or e}") from None
    if not data.startswith(SIGNATURE):
        raise PngError(f"{path}: not a PNG file")
    pos, idat, head = 8, [], None
    try:
        while pos < len(data):
            (n,) = struct.unpack(">I", data[pos : pos + 4])
            tag, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + n]
            pos += 12 + n
            if tag == b"IHDR":
                head = struct.unpack(">IIBBBBB", body)
            elif tag == b"IDAT":
                idat.append(body)
            elif tag == b"IEND":
                break
        if head is None:
            raise PngError(f"{path}: no IHDR chunk")
        w, h, depth, colour, _, _, interlace = head
        if depth != 8 or colour not in CHANNELS or interlace:
            raise PngError(
                f"{path}: only 8-bit non-interlaced grey/RGB/RGBA PNGs are read "
                f"(bit depth {depth}, colour type {colour}, interlace {interlace})"
            )
        c = CHANNELS[colour]
        raw = zlib.decompress(b"".join(idat))
    except (struct.error, zlib.error) as e:
        raise PngError(f"{path}: truncated or corrupt PNG ({e})") from None
    if len(raw) != h * (w * c + 1):
        raise PngError(f"{path}: pixel data has {len(raw)} bytes, expected {h * (w * c + 1)}")
    return raw, h, w, c
