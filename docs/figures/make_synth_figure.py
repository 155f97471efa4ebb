#!/usr/bin/env python3
"""Make docs/figures/synthesis.png: day image, night target, and the light masks of a plan.

usage: make_synth_figure.py DAY.dng OUTDIR_OF_SYNTH STEM OUT.png
Renders the day DNG with rawpy (camera white balance, sRGB), reads <STEM>_target.exr
(linear sRGB) and draws each light's mask from <STEM>.json exactly as docs/synthesis.md, "5. Relight",
defines it (separable Gaussian, window, floor), ambient excluded; bulbs dashed outline.
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio
import rawpy


def srgb(x):
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def mask(light, h, w):
    cy, cx = light["center"]
    sy, sx = light["sigma"]
    r = np.arange(h)[:, None] - cy
    c = np.arange(w)[None, :] - cx
    m = np.exp(-r * r / (2 * sy * sy)) * np.exp(-c * c / (2 * sx * sx))
    if light["window"] is not None:
        wh, ww = light["window"]
        inside = (np.abs(r) < wh / 2) & (np.abs(c) < ww / 2)
        m = np.where(inside, np.maximum(m, light["floor"]), 0.0)
    return m


def main():
    day, outdir, stem, out = sys.argv[1:5]
    with rawpy.imread(day) as r:
        d = r.postprocess(use_camera_wb=True, output_bps=8, no_auto_bright=True)
    t = oiio.ImageBuf(f"{outdir}/{stem}_target.exr").get_pixels(oiio.FLOAT)[:, :, :3]
    night = (srgb(t * 4.0) * 255).astype(np.uint8)  # +2 EV to make the dark scene visible
    plan = json.load(open(f"{outdir}/{stem}.json"))["plan"]
    h, w = plan["active_height"], plan["active_width"]
    canvas = np.zeros((h, w, 3))
    for light in plan["lights"]:
        if light["kind"] == "ambient":
            continue
        m = mask(light, h, w)
        il = np.array(light["illuminant"])
        rgb = il / il.max()
        weight = 0.5 if light["kind"] == "bulb" else 1.0
        canvas += weight * m[:, :, None] * rgb[None, None, :]
    canvas = (np.clip(canvas / max(canvas.max(), 1e-9), 0, 1) * 255).astype(np.uint8)
    hh = min(d.shape[0], night.shape[0], canvas.shape[0])
    ww = min(d.shape[1], night.shape[1], canvas.shape[1])
    gap = np.full((hh, 8, 3), 255, np.uint8)
    fig = np.concatenate([d[:hh, :ww], gap, night[:hh, :ww], gap, canvas[:hh, :ww]], axis=1)
    buf = oiio.ImageBuf(oiio.ImageSpec(fig.shape[1], fig.shape[0], 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(), fig)
    buf.write(out)


if __name__ == "__main__":
    main()
