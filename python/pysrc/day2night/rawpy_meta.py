"""Raws that rawpy (LibRaw) reads, as day2night Raws: ``from_rawpy``.

rawpy is not a dependency: the object is duck-typed (any object with the rawpy attributes
used below works). Which rawpy field feeds which ``Raw.meta`` key is documented in
docs/python.md ("Raws from other sources").
"""

import numpy as np

from ._native import XYZ_TO_SRGB, Raw

# XYZ (D65) -> linear sRGB (IEC 61966-2-1), the matrix LibRaw's ``color_matrix`` (camera ->
# sRGB) ends with: the library's one definition (day2night::color::xyz::XYZ_TO_SRGB).
_XYZ_TO_SRGB = np.array(XYZ_TO_SRGB, dtype=np.float64)

# LibRaw's ``sizes.flip`` -> EXIF/DNG Orientation.
_FLIP_TO_ORIENTATION = {0: 1, 3: 3, 5: 8, 6: 6}


def _letters(rp):
    desc = rp.color_desc
    if isinstance(desc, (bytes, bytearray)):
        desc = desc.decode("ascii", "replace")
    return str(desc)


def _colour_rows(rp, letters):
    """Indices of the R, G and B colour planes of LibRaw (``color_desc`` order)."""
    rows = []
    for want in "RGB":
        if want not in letters:
            raise ValueError(f"rawpy color_desc {letters!r} has no {want} plane: not an RGB camera")
        rows.append(letters.index(want))
    return rows


def _color_matrix(rp, rows):
    """XYZ (D65) -> camera, row-major, or None when LibRaw has none."""
    m = np.asarray(getattr(rp, "rgb_xyz_matrix", np.zeros((4, 3))), dtype=np.float64)
    if m.shape[0] >= 3 and m.shape[-1] == 3 and np.any(m[rows] != 0):
        return m[rows].ravel().tolist()
    # DNG input: LibRaw keeps only its camera -> sRGB matrix (rows scaled so that D65 white
    # gives camera (1, 1, 1) after the daylight multipliers): undo both.
    cam_to_srgb = np.asarray(getattr(rp, "color_matrix", np.zeros((3, 4))), dtype=np.float64)
    daylight = np.asarray(getattr(rp, "daylight_whitebalance", [0, 0, 0, 0]), dtype=np.float64)
    if cam_to_srgb.shape[0] < 3 or cam_to_srgb.shape[1] < len(set(rows)) or not np.all(daylight[rows] > 0):
        return None
    a = cam_to_srgb[:3][:, rows]
    if not np.all(np.isfinite(a)) or abs(np.linalg.det(a)) < 1e-12:
        return None
    m = np.diag(1.0 / daylight[rows]) @ np.linalg.inv(a) @ _XYZ_TO_SRGB
    return m.ravel().tolist() if np.all(np.isfinite(m)) else None


def rawpy_meta(rp):
    """The data array and ``Raw.meta`` dict of a rawpy object (see ``from_rawpy``); keys
    LibRaw does not know are left out (``from_array`` then applies its defaults)."""
    raw_type = getattr(rp, "raw_type", 0)
    if int(getattr(raw_type, "value", raw_type)) != 0:
        raise ValueError(f"rawpy raw_type {raw_type}: not a one-plane (Bayer) raw")
    letters = _letters(rp)
    rows = _colour_rows(rp, letters)
    s = rp.sizes
    data = rp.raw_image
    top, left = int(s.top_margin), int(s.left_margin)
    h, w = int(s.height), int(s.width)
    if data.shape == (h, w):
        top = left = 0
    elif top + h > data.shape[0] or left + w > data.shape[1]:
        data, top, left = rp.raw_image_visible, 0, 0
    colours = np.asarray(rp.raw_colors_visible[:2, :2])
    try:
        cfa = "".join(letters[int(c)] for c in colours.ravel())
    except IndexError:
        raise ValueError(f"rawpy raw colour indices {colours.tolist()} outside color_desc {letters!r}")
    per_channel = [float(v) for v in rp.black_level_per_channel]
    black = [per_channel[int(c)] for c in colours.ravel()]
    meta = {
        "cfa_pattern": cfa,
        "black_level": black[:1] if len(set(black)) == 1 else black,
        "black_level_repeat_dim": (1, 1) if len(set(black)) == 1 else (2, 2),
        "white_level": float(rp.white_level),
        "active_area": [top, left, top + h, left + w],
        "orientation": _FLIP_TO_ORIENTATION.get(int(getattr(s, "flip", 0)), 1),
        "linearization_table": None,  # LibRaw's raw_image is already linearized
    }
    ct, cl = int(getattr(s, "crop_top_margin", 0)), int(getattr(s, "crop_left_margin", 0))
    ch, cw = int(getattr(s, "crop_height", 0)), int(getattr(s, "crop_width", 0))
    if ch > 0 and cw > 0 and top <= ct and left <= cl and ct + ch <= top + h and cl + cw <= left + w:
        meta["default_crop"] = [ct - top, cl - left, ch, cw]
    wb = np.asarray(rp.camera_whitebalance, dtype=np.float64)
    if len(wb) >= 3 and np.all(wb[rows] > 0) and np.all(np.isfinite(wb[rows])):
        # Multipliers -> neutral (the camera's response to the white): their inverses.
        r, g, b = (1.0 / wb[i] for i in rows)
        meta["as_shot_neutral"] = [r / g, 1.0, b / g]
    cm = _color_matrix(rp, rows)
    if cm is not None:
        meta["color_matrix1"] = cm
        meta["calibration_illuminant1"] = 21  # LibRaw's matrices are D65 ones
    other = getattr(rp, "other", None)
    if other is not None:
        iso = float(getattr(other, "iso_speed", 0) or 0)
        if iso >= 1:
            meta["iso"] = int(round(iso))
        t = float(getattr(other, "shutter_speed", 0) or 0)
        if t > 0:
            meta["exposure_time"] = t
        f = float(getattr(other, "aperture", 0) or 0)
        if f > 0:
            meta["f_number"] = f
    return data, meta


def from_rawpy(rp, name, **meta):
    """A ``Raw`` from a ``rawpy`` object (any camera raw LibRaw reads: ARW, NEF, CR2, ...).

    ``name`` is the file stem the outputs and random streams are keyed by. Keyword
    arguments set or override ``Raw.meta`` keys LibRaw does not give (``make``, ``model``,
    ``noise_profile``, ``iso``, ...). Missing colour metadata gets ``Raw.from_array``'s
    defaults, each with a warning. rawpy is not imported: any object with its attributes
    works.

    >>> import rawpy
    >>> with rawpy.imread("a.nef") as rp:
    ...     raw = day2night.from_rawpy(rp, "a", make="Nikon", model="D750")
    >>> day2night.write_dng(raw, "a.dng")
    """
    data, m = rawpy_meta(rp)
    m.update(meta)
    return Raw.from_array(np.asarray(data), m, name=name)
