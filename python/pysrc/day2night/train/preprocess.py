"""The night ISP's network input, as the authors' release builds it (utils/data_generator.py
and test.py run their camera pipeline up to its demosaic stage, then raise to 1/2.2).

From a raw's active area (no DefaultCrop, no orientation: the stored orientation):

1. linearization table, when the file has one (value = table[min(x, len - 1)]);
2. black/white normalization per 2x2 CFA site: ``max(x - black, 0) / (white - black)``
   (BlackLevelDeltaH/V are not applied, as in the release);
3. white balance: each CFA site divided by the neutral component of its colour, as stored
   (the release does not renormalize it to green = 1), clipped to [0, 1];
4. demosaic: the release quantizes to 14 bits (``uint16(x * 16383)``, truncated), runs
   OpenCV's bilinear Bayer demosaic (``cv2.cvtColor(..., COLOR_BAYER_*2RGB)``) and divides by
   16383;
5. gamma: ``x ** (1 / 2.2)`` (``gamma=None`` keeps the linear values).

Steps 1-4 are the extension's (``day2night.release_codes``, ``day2night.demosaic_bilinear``:
src/isp/release_input.rs, OpenCV's integer rounding and border rule, so OpenCV is not a
dependency); step 5 maps the 14-bit codes through a table of numpy's float32
``(code / 16383) ** gamma``, the release's own arithmetic. python/tests/release_input_oracle.py
keeps the numpy formulation of steps 1-4 as a test oracle.

The neutral is the raw's AsShotNeutral at test time; for synthetic training pairs the
release uses the average night illuminant of the image (``synthesize(...)["neutral"]`` in
the local mode, the mean of the sampled lights). No torch here.
"""

import numpy as np

from .._native import demosaic_bilinear, release_codes

__all__ = ["GAMMA", "DEMOSAIC_SCALE", "demosaic_bilinear", "release_codes",
           "network_input_array", "network_input", "active_plane"]

#: The release's gamma exponent.
GAMMA = 1 / 2.2
#: The 14-bit scale of the release's demosaic stage.
DEMOSAIC_SCALE = 16383


def network_input_array(plane, meta, neutral=None, top=0, left=0, gamma=GAMMA):
    """The network input (H x W x 3 float32) of a CFA plane: ``plane`` is the active area
    (2-D uint16, or a crop of it at (``top``, ``left``)), ``meta`` a ``Raw.meta``-like dict
    (``black_level``, ``black_level_repeat_dim``, ``white_level``, ``cfa_pattern``, optional
    ``linearization_table`` and ``as_shot_neutral``); ``neutral`` defaults to
    ``meta["as_shot_neutral"]``. ``gamma=None``: linear, else ``x ** gamma``."""
    return _table(gamma)[release_codes(plane, meta, neutral, top, left)]


_TABLES = {}


def _table(gamma):
    """The 16,384 float32 values of the 14-bit codes: ``code / 16383``, ``** gamma``."""
    key = None if gamma is None else float(gamma)
    t = _TABLES.get(key)
    if t is None:
        t = np.arange(DEMOSAIC_SCALE + 1, dtype=np.float32) / np.float32(DEMOSAIC_SCALE)
        if key is not None:
            t = t ** np.float32(key)
        _TABLES[key] = t
    return t


def active_plane(raw):
    """The active area of a ``day2night.Raw`` CFA plane (a view of ``raw.data``)."""
    t, l, b, r = raw.meta["active_area"]
    data = raw.data
    if data.ndim != 2:
        raise ValueError(f"{raw.name}: a LinearRaw image has no CFA mosaic to demosaic")
    return data[t:b, l:r]


def network_input(raw, neutral=None, gamma=GAMMA):
    """The release's network input of a ``day2night.Raw`` (``read_dng``, ``Raw.from_array``):
    its active area, normalized, white-balanced by ``neutral`` (default: its AsShotNeutral),
    demosaiced bilinearly and raised to ``gamma`` (None: linear). H x W x 3 float32 in the
    stored orientation."""
    return network_input_array(active_plane(raw), raw.meta, neutral, 0, 0, gamma)
