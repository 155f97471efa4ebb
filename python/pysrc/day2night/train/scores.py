"""Scores of 8-bit sRGB predictions, as the release's test.py computes them, plus the
paper's mean Delta E 2000 (Table 1; the release has no code for it). No torch here.

- PSNR: ``10 log10(255^2 / MSE)`` over all samples (scikit-image's
  ``peak_signal_noise_ratio(target, pred, data_range=255)``).
- SSIM: scikit-image's conventions, ``data_range=255``, a 7x7 uniform window, sample
  covariance (N - 1), the mean over the valid (unpadded) window positions, then over the 3
  channels (``structural_similarity(target, pred, channel_axis=-1, data_range=255)``, the
  release's ``compare_ssim(..., multichannel=True, data_range=255)``).
- Delta E: the mean CIEDE2000 of the two images read as display sRGB.

All three are day2night's own metrics (``day2night.psnr``, ``ssim``, ``delta_e2000``, the
numbers ``day2night eval`` prints); a test checks them against scikit-image.
"""

import numpy as np

from .._native import delta_e2000, psnr, ssim


def _u8(a, what):
    a = np.asarray(a)
    if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"{what} must be a uint8 H x W x 3 image, got {a.dtype} {a.shape}")
    return a


def score(pred, target):
    """``{"psnr", "ssim", "delta_e"}`` of a uint8 H x W x 3 prediction against its target."""
    p, t = _u8(pred, "pred"), _u8(target, "target")
    if p.shape != t.shape:
        raise ValueError(f"pred {p.shape} and target {t.shape} differ in size")
    # as `day2night eval` reads an 8-bit PNG: v / 255 in float32, data range 1 (the same
    # PSNR and SSIM as data range 255 on the integers, up to float rounding)
    pf = p.astype(np.float32) / np.float32(255)
    tf = t.astype(np.float32) / np.float32(255)
    return {
        "psnr": float(psnr(pf, tf, data_range=1.0)),
        "ssim": float(ssim(pf, tf, data_range=1.0, window="uniform")),
        "delta_e": float(delta_e2000(pf, tf, pred_linear=False, target_linear=False)),
    }


def score_set(pairs):
    """Per-image scores and their means: ``pairs`` yields (name, pred, target). Returns
    ``{"images": [{"name", "psnr", "ssim", "delta_e"}, ...], "mean": {...}}`` (the mean of
    the per-image scores, as the release averages them; an infinite PSNR of an exact
    prediction makes the mean infinite)."""
    rows = []
    for name, pred, target in pairs:
        s = score(pred, target)
        s["name"] = str(name)
        rows.append(s)
    if not rows:
        raise ValueError("score_set: no images to score")
    mean = {k: float(np.mean([r[k] for r in rows])) for k in ("psnr", "ssim", "delta_e")}
    return {"images": rows, "mean": mean}
