#!/usr/bin/env python3
"""Compare day2night's linear sRGB render of a DNG with LibRaw's (rawpy) linear sRGB
development: postprocess(gamma=(1,1), no_auto_bright=True, use_camera_wb=True,
output_color=sRGB, output_bps=16).

usage: isp_rawpy.py DNG OURS.exr ACTIVE_TOP ACTIVE_LEFT ORIENT(0|1) MIN_PSNR

OURS.exr must be rendered without DefaultCrop (LibRaw ignores it) and, when ORIENT is 0,
without orientation (then LibRaw is run with user_flip=0). Pixels are matched through the
active-area origin and LibRaw's margins. One least-squares gain matches exposure; a 4-pixel
border and pixels clipped in either image are excluded. Prints a JSON line; exit 1 when the
PSNR (data range 1) is below MIN_PSNR, or when our absolute exposure differs from LibRaw's
by more than 10 % once LibRaw's adjust_maximum rescaling is turned off.
"""
import json
import sys

import numpy as np
import OpenEXR
import rawpy


def read_exr(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            px = ch["RGB"].pixels
        else:
            px = np.stack([ch[c].pixels for c in "RGB"], -1)
    return px.astype(np.float64)


def main():
    dng, ours_path, top, left, orient, min_psnr = sys.argv[1:7]
    top, left, orient, min_psnr = int(top), int(left), int(orient), float(min_psnr)
    ours = read_exr(ours_path)
    with rawpy.imread(dng) as r:
        s = r.sizes
        kw = dict(gamma=(1, 1), no_auto_bright=True, use_camera_wb=True,
                  output_color=rawpy.ColorSpace.sRGB, output_bps=16)
        if not orient:
            kw["user_flip"] = 0
        ref = r.postprocess(**kw).astype(np.float64) / 65535.0
        # LibRaw rescales to the data maximum when it exceeds 0.75 of the white level
        # (adjust_maximum_thr); without that our absolute scale must agree too.
        ref_abs = r.postprocess(adjust_maximum_thr=0.0, **kw).astype(np.float64) / 65535.0
        margins = (s.top_margin, s.left_margin)
    dy, dx = top - margins[0], left - margins[1]
    if orient and (dy, dx) != (0, 0):
        print(json.dumps({"error": "orientation check needs LibRaw margins equal to the active area"}))
        sys.exit(2)
    # ours[y, x] <-> ref[y + dy, x + dx]
    y0, x0 = max(0, -dy), max(0, -dx)
    y1 = min(ours.shape[0], ref.shape[0] - dy)
    x1 = min(ours.shape[1], ref.shape[1] - dx)
    b = 4
    a = ours[y0 + b:y1 - b, x0 + b:x1 - b]
    c = ref[y0 + b + dy:y1 - b + dy, x0 + b + dx:x1 - b + dx]
    c_abs = ref_abs[y0 + b + dy:y1 - b + dy, x0 + b + dx:x1 - b + dx]
    if a.shape != c.shape or a.size == 0:
        print(json.dumps({"error": f"shapes {ours.shape} vs {ref.shape} do not overlap"}))
        sys.exit(2)
    ok = (a.max(-1) < 0.98) & (c.max(-1) < 0.98)
    ok &= np.isfinite(a).all(-1)
    av, cv = a[ok], c[ok]
    gain = float((av * cv).sum() / max((av * av).sum(), 1e-30))
    mse = float(((gain * av - cv) ** 2).mean())
    psnr = 10 * np.log10(1.0 / max(mse, 1e-30))
    ok_abs = ok & (c_abs.max(-1) < 0.98)
    gain_abs = float((a[ok_abs] * c_abs[ok_abs]).sum() / max((a[ok_abs] ** 2).sum(), 1e-30))
    per_channel = ((a[ok_abs] * c_abs[ok_abs]).sum(0) / (a[ok_abs] ** 2).sum(0)).tolist()
    # a wrong flip or a shifted grid would show as a much better fit at another offset
    res = {
        "psnr": psnr, "gain": gain, "gain_without_adjust_maximum": gain_abs,
        "per_channel_gain_without_adjust_maximum": per_channel, "pixels": int(ok.sum()), "ours_shape": list(ours.shape),
        "libraw_shape": list(ref.shape), "offset": [dy, dx],
        "mean_ours": (gain * av).mean(0).tolist(), "mean_libraw": cv.mean(0).tolist(),
        "finite": bool(np.isfinite(ours).all()),
    }
    print(json.dumps(res))
    if not res["finite"] or psnr < min_psnr or not 0.9 < gain_abs < 1.1:
        sys.exit(1)


if __name__ == "__main__":
    main()
