#!/usr/bin/env python3
"""Make docs/figures/burst.png: a night burst's frames, its motion path, and a still burst's
merge against one of its frames.

usage: make_burst_figure.py DAY2NIGHT_BINARY DAY.dng OUT.png
(from the repository: `python docs/figures/make_burst_figure.py target/release/day2night
fixtures/day.dng docs/figures/burst.png`, with rawpy, numpy and Pillow installed)

Runs, in a temporary folder:
  synth DAY --burst 8 --iso 3200 --shake-step 2 --seed 1      (a shaken burst; the step is
                                                               larger than the default so the
                                                               motion shows at this size)
  synth DAY --burst 8 --iso 3200 --motion none --seed 1, then merge of its 8 frames
Top row: frames 00, 03, 05 and 07 (the centre 240 x 240 samples shown as their 2x2 blocks,
camera white balance, +1 EV) with a cross at the same image position. Bottom: the motion path
(dx, dy of the image centre per frame, from the sidecar; rotation written beside each
point), one frame of the still burst, and the merge of the 8 (noise variance / 8).
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import rawpy
from PIL import Image, ImageDraw


def render(path, box, gain):
    """The 2x2 blocks of the mosaic as RGB (half resolution: no demosaic to confuse the
    comparison), black-subtracted, scaled to [0, 1], white-balanced, times `gain`, sRGB."""
    with rawpy.imread(path) as r:
        v = r.raw_image_visible.astype(np.float64)
        black = np.array(r.black_level_per_channel, dtype=np.float64)
        white = float(r.white_level)
        pat = r.raw_pattern
        wb = np.array(r.camera_whitebalance[:3], dtype=np.float64)
        col = r.color_desc.decode()
    planes = {}
    for i in range(2):
        for j in range(2):
            ch = "RGB".index(col[pat[i, j]]) if col[pat[i, j]] in "RGB" else 1
            p = (v[i::2, j::2] - black[pat[i, j]]) / (white - black.max())
            planes.setdefault(ch, []).append(p)
    rgb = np.stack([np.mean(planes[c], axis=0) * wb[c] / wb[1] for c in range(3)], axis=-1)
    y0, x0, s = box
    t = np.clip(rgb[y0:y0 + s, x0:x0 + s] * gain, 0, 1)
    t = np.where(t <= 0.0031308, 12.92 * t, 1.055 * np.power(t, 1 / 2.4) - 0.055)
    return Image.fromarray((t * 255).astype(np.uint8))


def main():
    binary, day, out = sys.argv[1:4]
    with tempfile.TemporaryDirectory() as td:
        shake, still = os.path.join(td, "shake"), os.path.join(td, "still")
        common = [day, "--burst", "8", "--iso", "3200", "--seed", "1", "--target", "none", "-q"]
        subprocess.run([binary, "synth", "-o", shake, "--shake-step", "2"] + common, check=True)
        subprocess.run([binary, "synth", "-o", still, "--motion", "none"] + common, check=True)
        stem = os.path.splitext(os.path.basename(day))[0]
        frames = [os.path.join(still, f"{stem}_iso3200_f{k:02d}.dng") for k in range(8)]
        merged = os.path.join(td, "merged.dng")
        subprocess.run([binary, "merge"] + frames + ["-o", merged], check=True,
                       capture_output=True)
        plan = json.load(open(os.path.join(shake, f"{stem}.json")))["plan"]
        h, w = plan["active_height"], plan["active_width"]
        s = 120
        box = ((h // 2 - s) // 2, (w // 2 - s) // 2, s)
        gain = 2.0
        tiles = [render(os.path.join(shake, f"{stem}_iso3200_f{k:02d}.dng"), box, gain)
                 for k in (0, 3, 5, 7)]
        single = render(frames[0], box, gain)
        mean = render(merged, box, gain)
        tr = plan["burst"]["transforms"]

    scale = 3
    size = s * scale
    gap = 10
    W = 4 * size + 3 * gap
    H = 2 * size + gap + 20
    fig = Image.new("RGB", (W, H), "white")
    draw = ImageDraw.Draw(fig)
    for i, (t, k) in enumerate(zip(tiles, (0, 3, 5, 7))):
        x = i * (size + gap)
        fig.paste(t.resize((size, size), Image.NEAREST), (x, 0))
        c = x + size // 2
        draw.line([(c - 8, size // 2), (c + 8, size // 2)], fill=(255, 80, 80))
        draw.line([(c, size // 2 - 8), (c, size // 2 + 8)], fill=(255, 80, 80))
        draw.text((x + 4, 4), f"frame {k:02d}", fill=(255, 255, 0))
    # motion path panel
    y = size + gap
    px0, py0 = 0, y
    draw.rectangle([px0, py0, px0 + 2 * size + gap, py0 + size], outline=(0, 0, 0))
    xs = [t["dx"] for t in tr]
    ys = [t["dy"] for t in tr]
    span = max(1.0, max(abs(v) for v in xs + ys)) * 1.2
    cx, cy = px0 + (2 * size + gap) // 2, py0 + size // 2
    k = (size / 2 - 10) / span
    pts = [(cx + a * k, cy + b * k) for a, b in zip(xs, ys)]
    draw.line(pts, fill=(30, 90, 200), width=2)
    for i, (p, t) in enumerate(zip(pts, tr)):
        draw.ellipse([p[0] - 3, p[1] - 3, p[0] + 3, p[1] + 3], fill=(30, 90, 200))
        draw.text((p[0] + 5, p[1] - 5), f"{i:02d} {t['theta_deg']:+.3f} deg", fill=(0, 0, 0))
    draw.text((px0 + 6, py0 + 4),
              f"motion of the image centre (px, y down; +-{span:.1f} px shown)", fill=(0, 0, 0))
    x = 2 * (size + gap)
    fig.paste(single.resize((size, size), Image.NEAREST), (x, y))
    draw.text((x + 4, y + 4), "still burst: one frame", fill=(255, 255, 0))
    x = 3 * (size + gap)
    fig.paste(mean.resize((size, size), Image.NEAREST), (x, y))
    draw.text((x + 4, y + 4), "merge of 8 frames", fill=(255, 255, 0))
    fig.save(out)


if __name__ == "__main__":
    main()
