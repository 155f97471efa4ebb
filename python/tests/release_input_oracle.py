"""The numpy formulation of the release's network input (steps 1-4 of
day2night.train.preprocess), kept as the oracle of the extension's
(``day2night.release_codes``, ``day2night.demosaic_bilinear``: src/isp/release_input.rs).
test_release_input_oracle.py shows the two equal; the package itself has no numpy copy."""

import numpy as np

DEMOSAIC_SCALE = 16383

_COLOURS = {"R": 0, "G": 1, "B": 2}


def cfa_indices(pattern):
    """``"RGGB"`` (or a sequence of 4 colour indices) to 4 ints in 0..2, in the order of the
    2x2 positions (0,0), (0,1), (1,0), (1,1)."""
    if isinstance(pattern, str):
        if len(pattern) != 4 or any(c not in _COLOURS for c in pattern.upper()):
            raise ValueError(f"CFA pattern {pattern!r}: need a 2x2 Bayer pattern such as 'RGGB'")
        idx = [_COLOURS[c] for c in pattern.upper()]
    else:
        idx = [int(c) for c in pattern]
    greens_diagonal = len(idx) == 4 and ((idx[0] == idx[3] == 1) or (idx[1] == idx[2] == 1))
    if len(idx) != 4 or sorted(idx) != [0, 1, 1, 2] or not greens_diagonal:
        raise ValueError(f"CFA pattern {pattern!r} is not a 2x2 Bayer pattern (one R, one B, "
                         "two G on a diagonal)")
    return idx


def _site_values(values, repeat, top, left):
    """Per 2x2 site (top+i, left+j) the value of a BlackLevel pattern of ``repeat`` rows x cols."""
    values = [float(v) for v in np.ravel(values)]
    rr, rc = (int(repeat[0]), int(repeat[1])) if repeat else (1, 1)
    if len(values) == 1:
        return [values[0]] * 4
    if len(values) != rr * rc:
        raise ValueError(f"black level {values} does not fill its {rr}x{rc} repeat pattern")
    return [values[((top + i) % rr) * rc + (left + j) % rc] for i in (0, 1) for j in (0, 1)]


def normalize(plane, black, white, top=0, left=0, repeat=None, linearization=None):
    """Steps 1-2: float32 ``max(x - black, 0) / (white - black)`` per 2x2 site."""
    x = np.asarray(plane)
    if x.ndim != 2:
        raise ValueError(f"a CFA plane must be 2-D, got shape {x.shape}")
    if linearization is not None and len(linearization):
        lut = np.asarray(linearization, dtype=np.float64)
        x = lut[np.minimum(x.astype(np.int64), len(lut) - 1)]
    out = x.astype(np.float32)
    for k, b in enumerate(_site_values(black, repeat, top, left)):
        i, j = divmod(k, 2)
        scale = float(white) - b
        if not scale > 0:
            raise ValueError(f"black level {b} >= white level {white}")
        site = out[i::2, j::2]
        site -= np.float32(b)
        np.maximum(site, 0, out=site)
        site /= np.float32(scale)
    return out


def white_balance(norm, neutral, cfa):
    """Step 3: each site divided by ``neutral[colour]``, clipped to [0, 1]."""
    neutral = [float(v) for v in neutral]
    if len(neutral) != 3 or not all(v > 0 and np.isfinite(v) for v in neutral):
        raise ValueError(f"neutral {neutral}: need 3 positive finite components")
    out = np.array(norm, dtype=np.float32)
    for k, c in enumerate(cfa_indices(cfa)):
        i, j = divmod(k, 2)
        site = out[i::2, j::2]
        site /= np.float32(neutral[c])
    return np.clip(out, 0.0, 1.0, out=out)


def demosaic_bilinear(mosaic, cfa):
    """OpenCV's bilinear Bayer demosaic of an integer mosaic (H x W, H and W >= 3), as
    ``cv2.cvtColor`` computes it: at a red or blue site green is the rounded mean of the 4
    neighbours ``(a + b + c + d + 2) >> 2`` and the other colour that of the 4 diagonals; at
    a green site each other colour is the rounded mean ``(a + b + 1) >> 1`` of the two
    neighbours of that colour. The first and last rows and columns copy their inner
    neighbours. Returns H x W x 3 (R, G, B) of the input's dtype."""
    m = np.asarray(mosaic)
    if m.ndim != 2:
        raise ValueError(f"bilinear demosaic needs a 2-D mosaic, got shape {m.shape}")
    h, w = m.shape
    if h < 3 or w < 3:
        raise ValueError(f"bilinear demosaic needs at least 3x3 samples, got {w}x{h}")
    idx = cfa_indices(cfa)
    v = m.astype(np.int32)
    out = np.empty((h, w, 3), dtype=m.dtype)
    # the inner sites of each of the 4 CFA phases, as strided views
    for pi in (0, 1):
        y0 = pi if pi else 2
        ny = len(range(y0, h - 1, 2))
        for pj in (0, 1):
            x0 = pj if pj else 2
            nx = len(range(x0, w - 1, 2))
            if ny == 0 or nx == 0:
                continue

            def at(dy, dx, y0=y0, x0=x0, ny=ny, nx=nx):
                return v[y0 + dy:y0 + dy + 2 * ny:2, x0 + dx:x0 + dx + 2 * nx:2]

            dst = out[y0:y0 + 2 * ny:2, x0:x0 + 2 * nx:2]
            c = idx[pi * 2 + pj]
            dst[..., c] = at(0, 0)
            if c == 1:
                # green site: the colour of the row's other site from the 2 horizontal
                # neighbours, the column's from the 2 vertical ones
                dst[..., idx[pi * 2 + 1 - pj]] = (at(0, -1) + at(0, 1) + 1) >> 1
                dst[..., idx[(1 - pi) * 2 + pj]] = (at(-1, 0) + at(1, 0) + 1) >> 1
            else:
                dst[..., 1] = (at(-1, 0) + at(1, 0) + at(0, -1) + at(0, 1) + 2) >> 2
                dst[..., 2 - c] = (at(-1, -1) + at(-1, 1) + at(1, -1) + at(1, 1) + 2) >> 2
    out[0] = out[1]
    out[-1] = out[-2]
    out[:, 0] = out[:, 1]
    out[:, -1] = out[:, -2]
    return out


def release_codes(plane, meta, neutral=None, top=0, left=0):
    """Steps 1-4 of a CFA plane: the demosaiced 14-bit codes (H x W x 3 uint16)."""
    if neutral is None:
        neutral = meta.get("as_shot_neutral")
        if neutral is None:
            raise ValueError("no neutral given and the raw has no AsShotNeutral")
    cfa = meta.get("cfa_pattern")
    if cfa is None:
        raise ValueError("the raw is not a Bayer CFA mosaic (no cfa_pattern)")
    # an odd offset moves the CFA phase: rotate the pattern so that it starts at the plane
    idx = cfa_indices(cfa)
    idx = [idx[((top + i) % 2) * 2 + (left + j) % 2] for i in (0, 1) for j in (0, 1)]
    norm = normalize(plane, meta["black_level"], meta["white_level"], top, left,
                     meta.get("black_level_repeat_dim"), meta.get("linearization_table"))
    wb = white_balance(norm, neutral, idx)
    wb *= np.float32(DEMOSAIC_SCALE)
    q = wb.astype(np.uint16)  # truncated, as the release's astype
    return demosaic_bilinear(q, idx)
