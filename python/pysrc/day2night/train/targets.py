"""The night ISP's target: the software ISP's 8-bit sRGB render (what ``day2night synth
--target png`` and ``day2night render -o x.png`` write), from day2night's linear target.

``srgb8`` is the command line's own quantizer (Rust, through ``day2night.encode_u8``): the
sRGB OETF of each sample clamped to [0, 1], ``* 255 + 0.5`` truncated, byte for byte the PNG
files. The network learns ``srgb8(...) / 255`` (the release's ``clean/*.png / 255``).
``render_target(raw, isp="release")`` is the release's own target ISP instead.
No torch here.
"""

import numpy as np

from .._native import (  # noqa: F401
    encode_u8, release_conflicts, release_window, render, render_release_u8,
)
from ..variants import Isp


def srgb8(linear, tone="srgb"):
    """uint8 H x W x 3 display encoding of linear Rec.709 RGB (``synthesize(...)["target"]``,
    ``render(raw)``; any float dtype, H x W x 3 or 3 x H x W as ``NightPairs`` items hold
    it): the bytes of the command line's PNG for ``tone`` ("srgb" default, "gamma22",
    "release")."""
    a = np.asarray(linear)
    if a.ndim == 3 and a.shape[0] == 3 and a.shape[-1] != 3:
        a = np.moveaxis(a, 0, -1)
    return encode_u8(np.ascontiguousarray(a), tone)


def render_target(raw, neutral=None, demosaic="mhc", tone="srgb", isp=Isp.DAY2NIGHT, orient=True):
    """The 8-bit sRGB target of a raw.

    ``isp="day2night"`` (default): aligned pixel for pixel with
    ``preprocess.network_input(raw)``: the software ISP's render of the active area, with no
    DefaultCrop and no orientation (``render(raw, crop=False, orient=False)``), encoded by
    ``srgb8``; ``orient`` is not used.

    ``isp="release"``: the authors' release's target, byte for byte ``day2night render --isp
    release`` (docs/isp.md): its image window (``release_window(raw)``, inside the active
    area) and its orientation (``orient=False``: before it). ``demosaic`` and ``tone`` may
    only name what it does (``"menon"``, ``"release"``) or be left out.

    ``neutral`` defaults to the raw's AsShotNeutral."""
    if isp == Isp.RELEASE:
        conflict = release_conflicts([("demosaic", demosaic), ("tone", tone)])
        if conflict is not None:
            name, value, own = conflict
            raise ValueError(f"{name}={value!r}: isp='release' uses {name}={own!r} "
                             "(leave it out)")
        return render_release_u8(raw, neutral=neutral, orient=orient)
    if isp != Isp.DAY2NIGHT:
        raise ValueError(f"isp={isp!r}: use 'day2night' or 'release'")
    return srgb8(render(raw, neutral=neutral, demosaic=demosaic, crop=False, orient=False), tone)


def as_float(target_u8):
    """A uint8 target as the network sees it: float32 in [0, 1] (``/ 255``)."""
    return np.asarray(target_u8, dtype=np.float32) / np.float32(255)
