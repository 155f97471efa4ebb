"""A compact, exact store for network inputs (the experiment's ``RUN/data`` cache and
``save_pair``): 2 bytes per pixel plus a border, against 12 for float32 H x W x 3.

The release's network input is ``table[demosaic_bilinear(q)]``: 14-bit CFA codes ``q``,
OpenCV's bilinear demosaic (``preprocess.demosaic_bilinear``), then a 16,384-entry float32
table (``code / 16383``, raised to the gamma). Cropping and turning the result (``align``)
only moves pixels. So an input can be stored as one 14-bit code per pixel (the code of the
pixel's own CFA colour) and demosaiced again on load, except next to the image's edges,
where the demosaic saw pixels that are gone (a crop) or copied a neighbour (the first and
last rows and columns). Those two outer rings are stored as they are (3 codes per pixel).

``encode(x)`` finds this form from the float input alone (the table, the CFA phase of the
turned image) and checks it: ``decode(encode(x))`` must give ``x`` bit for bit, else it
falls back to 3 codes per pixel (6 B/px) or, when ``x`` is not on a table at all, to the
float32 bits themselves (12 B/px); so the store is always exact. Layout: one 1-D uint16
array (a ``.npy`` file, memory-mapped by readers):

    header (16 values): MAGIC (2), VERSION, encoding, H (2), W (2), gamma id, CFA (4), 0...
    encoding CFA14: H*W codes, then the rings: rows 0, 1, H-2, H-1 (4 x W x 3 codes), then
                    columns 0, 1, W-2, W-1 of rows 2..H-3 ((H-4) x 4 x 3 codes)
    encoding RGB14: H*W*3 codes        encoding FLOAT32: H*W*3 float32 as 2 uint16 each

``decode_window`` decodes one patch from the memory map (the demosaic of the patch and a
1-pixel margin), so a training set costs its file size in memory, not 12 B/px.
"""

import numpy as np

from . import preprocess

MAGIC = (0x3264, 0x696E)  # "d2" "ni" little-endian
VERSION = 2
HEADER = 16
CFA14, RGB14, FLOAT32 = 1, 2, 3
ENCODINGS = {CFA14: "cfa14", RGB14: "rgb14", FLOAT32: "float32"}
#: gamma ids of the header: the tables an input can be on.
GAMMAS = {1: preprocess.GAMMA, 0: None}
#: 2x2 Bayer patterns (colour of positions (0,0), (0,1), (1,0), (1,1)).
PATTERNS = ((0, 1, 1, 2), (2, 1, 1, 0), (1, 0, 2, 1), (1, 2, 0, 1))


class CacheFormatError(ValueError):
    """A stored input that is not this format (the message names the file when known)."""


def is_encoded(a):
    """True for a 1-D uint16 array that starts with this format's magic (any version)."""
    return (isinstance(a, np.ndarray) and a.ndim == 1 and a.dtype == np.uint16
            and a.shape[0] >= HEADER and int(a[0]) == MAGIC[0] and int(a[1]) == MAGIC[1])


def _codes(x):
    """(gamma id, H x W x 3 uint16 codes) of an input on one of the tables, or None."""
    for gid, gamma in GAMMAS.items():
        t = preprocess._table(gamma)
        c = np.clip(np.searchsorted(t, x), 0, len(t) - 1).astype(np.uint16)
        if np.array_equal(t[c], x):
            return gid, c
    return None


def _ring(c):
    """The two outer rings of H x W x 3 codes (rows first, then the columns between)."""
    h, w = c.shape[:2]
    rows = c[[0, 1, h - 2, h - 1]]
    cols = c[2:h - 2][:, [0, 1, w - 2, w - 1]]
    return np.concatenate([rows.ravel(), cols.ravel()])


def _mosaic(c, pattern):
    """The code of each pixel's own colour under ``pattern``."""
    h, w = c.shape[:2]
    m = np.empty((h, w), np.uint16)
    for k, col in enumerate(pattern):
        i, j = divmod(k, 2)
        m[i::2, j::2] = c[i::2, j::2, col]
    return m


def _pattern(c):
    """The Bayer pattern whose bilinear demosaic gives ``c`` inside its rings, or None."""
    h, w = c.shape[:2]
    for p in PATTERNS:  # a small probe first, then the whole inner image
        probe = c[: min(h, 24), : min(w, 24)]
        d = preprocess.demosaic_bilinear(_mosaic(probe, p), p)
        if not np.array_equal(d[2:-2, 2:-2], probe[2:-2, 2:-2]):
            continue
        d = preprocess.demosaic_bilinear(_mosaic(c, p), p)
        if np.array_equal(d[2:-2, 2:-2], c[2:-2, 2:-2]):
            return p
    return None


def _header(enc, h, w, gid=0, pattern=(0, 0, 0, 0)):
    head = np.zeros(HEADER, np.uint16)
    head[:11] = (*MAGIC, VERSION, enc, h >> 16, h & 0xFFFF, w >> 16, w & 0xFFFF, gid,
                 pattern[0], pattern[1])
    head[11:13] = pattern[2:]
    return head


def encode(x):
    """The 1-D uint16 store of a float32 H x W x 3 input (always exact; see the module)."""
    x = np.ascontiguousarray(x, dtype=np.float32)
    if x.ndim != 3 or x.shape[2] != 3:
        raise ValueError(f"a network input is H x W x 3, got {x.shape}")
    h, w = x.shape[:2]
    found = _codes(x)
    if found is None:
        return np.concatenate([_header(FLOAT32, h, w), x.ravel().view(np.uint16)])
    gid, c = found
    p = _pattern(c) if h >= 6 and w >= 6 else None
    if p is None:
        return np.concatenate([_header(RGB14, h, w, gid), c.ravel()])
    out = np.concatenate([_header(CFA14, h, w, gid, p), _mosaic(c, p).ravel(), _ring(c)])
    if not np.array_equal(decode(out), x):  # pragma: no cover - the checks above imply it
        return np.concatenate([_header(RGB14, h, w, gid), c.ravel()])
    return out


def info(a, name="input"):
    """The header of a store: dict(encoding, height, width, gamma, pattern, version)."""
    if not is_encoded(a):
        raise CacheFormatError(f"{name}: not a day2night input store (no magic)")
    v = int(a[2])
    if v != VERSION:
        raise CacheFormatError(f"{name}: input store version {v}, this day2night reads "
                               f"{VERSION}: delete it to have it made again")
    enc = int(a[3])
    h, w = (int(a[4]) << 16) | int(a[5]), (int(a[6]) << 16) | int(a[7])
    gid = int(a[8])
    if enc not in ENCODINGS or gid not in GAMMAS:
        raise CacheFormatError(f"{name}: unknown encoding {enc} or gamma id {gid}")
    _check_header(a, name, enc, gid)
    size = {CFA14: h * w + 12 * w + 12 * max(h - 4, 0), RGB14: 3 * h * w,
            FLOAT32: 6 * h * w}[enc]
    if a.shape[0] != HEADER + size:
        raise CacheFormatError(f"{name}: {a.shape[0]} values, its header ({h}x{w}, "
                               f"{ENCODINGS[enc]}) needs {HEADER + size}: truncated or damaged")
    return {"encoding": enc, "height": h, "width": w, "gamma": GAMMAS[gid], "gamma_id": gid,
            "pattern": tuple(int(v) for v in a[9:13]), "version": v}


def _check_header(a, name, enc, gid):
    """The header values :func:`encode` writes: a Bayer pattern (CFA14) or zeros, a gamma
    id of 0 for the float32 bits, zeros after the pattern."""
    pattern = tuple(int(v) for v in a[9:13])
    if enc == CFA14 and pattern not in PATTERNS:
        raise CacheFormatError(f"{name}: CFA pattern {pattern} in its header is not a 2x2 "
                               "Bayer pattern (colours 0..2, one R, one B, two G on a "
                               "diagonal): damaged")
    if enc != CFA14 and any(pattern):
        raise CacheFormatError(f"{name}: CFA pattern {pattern} in the header of a "
                               f"{ENCODINGS[enc]} store (it has none): damaged")
    if enc == FLOAT32 and gid != 0:
        raise CacheFormatError(f"{name}: gamma id {gid} in the header of a float32 store "
                               "(it has none): damaged")
    if any(int(v) for v in a[13:HEADER]):
        raise CacheFormatError(f"{name}: header values 13..15 are not 0: damaged")


def gamma_id(gamma):
    """The header's id of a gamma (``GAMMAS``): 1 for the release's 1/2.2, 0 for linear."""
    return next(k for k, v in GAMMAS.items() if v == gamma)


def nbytes_per_pixel(a):
    """Bytes of the store (header included) per pixel of the input."""
    i = info(a)
    return a.nbytes / (i["height"] * i["width"])


def decode(a, name="input"):
    """The float32 H x W x 3 input of a store."""
    i = info(a, name)
    try:
        return decode_window(a, 0, 0, i["height"], i["width"], i)
    except CacheFormatError as e:
        raise CacheFormatError(str(e).replace("input store", name, 1)) from None


def _body(a, i):
    h, w = i["height"], i["width"]
    body = a[HEADER:]
    if i["encoding"] == FLOAT32:
        return body.view(np.float32).reshape(h, w, 3)
    if i["encoding"] == RGB14:
        return body.reshape(h, w, 3)
    return body[: h * w].reshape(h, w)


def decode_window(a, top, left, hh, ww, i=None):
    """Rows ``top:top+hh``, columns ``left:left+ww`` of the decoded input, computed from that
    window and a 1-pixel margin (the same bits as ``decode(a)[top:..., left:...]``)."""
    i = info(a) if i is None else i
    h, w = i["height"], i["width"]
    if not (0 <= top and top + hh <= h and 0 <= left and left + ww <= w):
        raise ValueError(f"window {top},{left} {hh}x{ww} outside the {h}x{w} input")
    body = _body(a, i)
    if i["encoding"] == FLOAT32:
        return np.array(body[top:top + hh, left:left + ww])
    t = preprocess._table(i["gamma"])
    if i["encoding"] == RGB14:
        return _lookup(t, body[top:top + hh, left:left + ww])
    r0, r1 = max(top - 1, 0), min(top + hh + 1, h)
    c0, c1 = max(left - 1, 0), min(left + ww + 1, w)
    p = i["pattern"]
    p = [p[((r0 + a_) % 2) * 2 + (c0 + b_) % 2] for a_ in (0, 1) for b_ in (0, 1)]
    win = np.ascontiguousarray(body[r0:r1, c0:c1])
    if win.shape[0] >= 3 and win.shape[1] >= 3:
        codes = preprocess.demosaic_bilinear(win, p)[top - r0:top - r0 + hh,
                                                     left - c0:left - c0 + ww]
    else:
        codes = np.zeros((hh, ww, 3), np.uint16)  # all of it lies on the rings
    _put_rings(codes, a, i, top, left)
    return _lookup(t, codes)


def _lookup(table, codes):
    """``table[codes]``; a code past the table (a damaged store) is a CacheFormatError."""
    if codes.size and int(codes.max()) >= len(table):
        raise CacheFormatError(f"input store: code {int(codes.max())} past the "
                               f"{len(table)}-entry table: damaged")
    return table[codes]


def _put_rings(codes, a, i, top, left):
    """Overwrite the window's pixels that lie on the image's two outer rings."""
    h, w = i["height"], i["width"]
    hh, ww = codes.shape[:2]
    ring = a[HEADER + h * w:]
    rows = ring[: 12 * w].reshape(4, w, 3)
    cols = ring[12 * w:].reshape(max(h - 4, 0), 4, 3)
    for k, r in enumerate((0, 1, h - 2, h - 1)):
        if top <= r < top + hh:
            codes[r - top] = rows[k, left:left + ww]
    r0, r1 = max(top, 2), min(top + hh, h - 2)
    if r1 > r0:
        for k, col in enumerate((0, 1, w - 2, w - 1)):
            if left <= col < left + ww:
                codes[r0 - top:r1 - top, col - left] = cols[r0 - 2:r1 - 2, k]
