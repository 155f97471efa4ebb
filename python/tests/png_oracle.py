"""The numpy/zlib PNG encoder the package had before it called the extension's
(``day2night.png_bytes``: src/encode/png_rows.rs), kept as the oracle of
test_png_oracle.py: the two files decode to the same samples."""

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_bytes(array) -> bytes:
    a = np.ascontiguousarray(array)
    if a.dtype != np.uint8:
        raise ValueError(f"PNG: 8-bit samples expected, got {a.dtype}")
    if a.ndim == 2:
        colour, a = 0, a[:, :, None]
    elif a.ndim == 3 and a.shape[2] == 3:
        colour = 2
    else:
        raise ValueError(f"PNG: (H, W) or (H, W, 3) expected, got {a.shape}")
    h, w, c = a.shape
    rows = np.concatenate([np.zeros((h, 1), np.uint8), a.reshape(h, w * c)], axis=1)

    def chunk(tag, body):
        crc = zlib.crc32(tag + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", crc)

    head = struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)
    return (
        SIGNATURE
        + chunk(b"IHDR", head)
        + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
        + chunk(b"IEND", b"")
    )


def png16_bytes(array) -> bytes:
    """A 16-bit grey (H, W) or RGB (H, W, 3) PNG of a uint16 array (big-endian samples, no
    filter): what the release's clean_raw/NNN.png files are."""
    a = np.ascontiguousarray(array, dtype=">u2")
    colour = 0 if a.ndim == 2 else 2
    h, w = a.shape[:2]
    rows = a.reshape(h, -1).view(np.uint8)
    rows = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1)

    def chunk(tag, body):
        crc = zlib.crc32(tag + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + tag + body + struct.pack(">I", crc)

    head = struct.pack(">IIBBBBB", w, h, 16, colour, 0, 0, 0)
    return (SIGNATURE + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(rows.tobytes()))
            + chunk(b"IEND", b""))
