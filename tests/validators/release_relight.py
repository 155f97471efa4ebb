"""Independent reference of the authors' release's clean night raw in local mode with
saturated bulbs, for a DNG with a per-site (2x2) black level (issue 26 point 2).

Usage: release_relight.py DAY.dng SIDECAR.json CLEAN.dng --black B00,B01,B10,B11 --white W

The sampled parameters (dimming, lights, bulb gains, day neutral) come from day2night's
sidecar; everything else is computed here with numpy from the release's documented
semantics (docs/synthesis.md, "Release compatibility"; the release's data preparation in
SamsungLabs/day-to-night), not from day2night's code:

- normalize per site with the site's own range: y = max(x - b, 0) / (W - b);
- divide by the day neutral as stored, clip to [0, 1]; dim by s;
- each light k relights the whole frame: R_k = clip(y_e / (1 / l_k[c] / a_k), 0, 1)
  (a = 0.05 for the ambient light, 1 otherwise);
- the ambient (mask 1) and local lights are averaged with their masks as weights;
- each bulb adds g * M * R (its gain g, its mask M, its relit frame R with a = 1);
- values above 1 become 1;
- denormalize per site: float32(y) * (W - b) + b, clipped to [0, W], truncated.

Masks are the release's kernels: cv2.getGaussianKernel(sz, sigma) of sz = max(h, w)
samples (OpenCV's bit-exact kernel: exp(-d^2 / (2 sigma^2)) at d = i - (sz - 1)/2 with the
centre sample, or both centre samples of an even kernel, exactly 1), outer product divided
by its maximum, resized to h x w by INTER_LINEAR (source position (j + 0.5) sz / n - 0.5,
clamped at both ends), floored at 1e-7, stored as float32 and placed with its first sample
at the first pixel inside the plan's window, floor(c - n/2) + 1; 0 outside. sigma is the
plan's sigma of the longer window axis.

Reads both DNGs with rawpy (LibRaw), as the release does. Prints one JSON object:
samples, max_abs_diff (DN), differing (> 0 DN), over_1 (> 1 DN), saturated (sites where the
reference is at 1 before denormalizing), bulb_lit (sites where a bulb adds > 1e-3).
"""

import argparse
import json
import sys

import numpy as np
import rawpy


def kernel_1d(sz, sigma):
    d = np.arange(sz, dtype=np.float64) - (sz - 1) / 2.0
    k = np.exp(-(d * d) / (2.0 * sigma * sigma))
    k[np.abs(d) <= 0.5] = 1.0
    return k


def resize_1d(k, n):
    sz = len(k)
    if n == sz:
        return k.copy()
    f = (np.arange(n, dtype=np.float64) + 0.5) * (sz / n) - 0.5
    s = np.floor(f)
    fx = f - s
    s = s.astype(np.int64)
    fx[s < 0] = 0.0
    s[s < 0] = 0
    out = np.empty(n)
    last = s >= sz - 1
    out[last] = k[sz - 1]
    i = s[~last]
    out[~last] = k[i] * (1.0 - fx[~last]) + k[i + 1] * fx[~last]
    return out


def mask(light, height, width):
    h, w = (int(round(v)) for v in light["window"])
    sz = max(h, w)
    sigma = light["sigma"][0] if h >= w else light["sigma"][1]
    k = kernel_1d(sz, sigma)
    m = np.outer(resize_1d(k, h), resize_1d(k, w))
    m = np.maximum(m, 1e-7).astype(np.float32)
    r0 = int(np.floor(light["center"][0] - h / 2.0)) + 1
    c0 = int(np.floor(light["center"][1] - w / 2.0)) + 1
    out = np.zeros((height, width), np.float32)
    ra, rb = max(r0, 0), min(r0 + h, height)
    ca, cb = max(c0, 0), min(c0 + w, width)
    if rb > ra and cb > ca:
        out[ra:rb, ca:cb] = m[ra - r0 : rb - r0, ca - c0 : cb - c0]
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("day")
    ap.add_argument("sidecar")
    ap.add_argument("clean")
    ap.add_argument("--black", required=True)
    ap.add_argument("--white", type=float, required=True)
    a = ap.parse_args()
    blacks = [float(v) for v in a.black.split(",")]
    white = a.white
    with rawpy.imread(a.day) as r:
        x = r.raw_image_visible.astype(np.float64)
        colors = r.raw_colors_visible.copy()
    with rawpy.imread(a.clean) as r:
        ours = r.raw_image_visible.astype(np.int64)
    colors[colors == 3] = 1
    height, width = x.shape
    b = np.zeros_like(x)
    for i, (dr, dc) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1)]):
        b[dr::2, dc::2] = blacks[i]
    plan = json.load(open(a.sidecar))["plan"]
    if plan["mode"] != "local" or plan["mask_eval"]["eval"] != "release":
        sys.exit("expects a local-mode plan with release masks")
    n = np.asarray(plan["day_neutral"])
    s = plan["dim"]["s"]
    y = np.maximum(x - b, 0.0) / (white - b)
    ye = np.clip(y / n[colors], 0.0, 1.0) * s
    num = np.zeros_like(x)
    den = np.zeros_like(x)
    bulbs = np.zeros_like(x)
    for light in plan["lights"]:
        ill = np.asarray(light["illuminant"])
        if light["kind"] == "bulb":
            rel = np.clip(ye / (1.0 / ill[colors]), 0.0, 1.0)
            add = light["gain"] * mask(light, height, width) * rel
            bulbs += add
            continue
        rel = np.clip(ye / (1.0 / ill[colors] / light["gain"]), 0.0, 1.0)
        m = 1.0 if light["kind"] == "ambient" else mask(light, height, width)
        num += m * rel
        den += m
    yr = num / den + bulbs
    saturated = int((yr >= 1.0).sum())
    yr = np.minimum(yr, 1.0)
    ref = yr.astype(np.float32).astype(np.float64) * (white - b) + b
    ref = np.clip(ref, 0.0, white).astype(np.int64)
    d = np.abs(ref - ours)
    print(
        json.dumps(
            {
                "samples": int(d.size),
                "max_abs_diff": int(d.max()),
                "differing": int((d > 0).sum()),
                "over_1": int((d > 1).sum()),
                "saturated": saturated,
                "bulb_lit": int((bulbs > 1e-3).sum()),
            }
        )
    )


if __name__ == "__main__":
    main()
