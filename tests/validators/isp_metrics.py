#!/usr/bin/env python3
"""Reference metrics for two images with scikit-image and colour-science.

usage: isp_metrics.py PRED TARGET DATA_RANGE
Images: PNG/TIFF (integers scaled to [0, 1], display sRGB) or EXR (linear). Prints JSON:
psnr (skimage.metrics.peak_signal_noise_ratio), ssim (structural_similarity with
channel_axis=-1), ssim_gaussian (gaussian_weights=True, sigma=1.5,
use_sample_covariance=False), delta_e_2000 (colour: sRGB -> XYZ -> Lab D65, CIE 2000 mean).
"""
import json
import sys

import colour
import numpy as np
import OpenEXR
import tifffile
from skimage import io as skio
from skimage.metrics import peak_signal_noise_ratio, structural_similarity


def load(path):
    if path.lower().endswith(".exr"):
        with OpenEXR.File(path) as f:
            ch = f.channels()
            px = ch["RGB"].pixels if "RGB" in ch else np.stack([ch[c].pixels for c in "RGB"], -1)
        return px.astype(np.float64), True
    if path.lower().endswith((".tif", ".tiff")):
        a = tifffile.imread(path)
    else:
        a = skio.imread(path)
    if a.ndim == 2:
        a = np.stack([a] * 3, -1)
    a = a[..., :3]
    if a.dtype == np.uint8:
        return a.astype(np.float64) / 255.0, False
    if a.dtype == np.uint16:
        return a.astype(np.float64) / 65535.0, False
    return a.astype(np.float64), True


def lab(img, linear):
    xyz = colour.RGB_to_XYZ(img, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=not linear)
    return colour.XYZ_to_Lab(xyz, colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])


def main():
    p, t, dr = sys.argv[1], sys.argv[2], float(sys.argv[3])
    a, al = load(p)
    b, bl = load(t)
    de = colour.delta_E(lab(a, al), lab(b, bl), method="CIE 2000")
    print(json.dumps({
        "psnr": float(peak_signal_noise_ratio(b, a, data_range=dr)),
        "ssim": float(structural_similarity(a, b, channel_axis=-1, data_range=dr)),
        "ssim_gaussian": float(structural_similarity(
            a, b, channel_axis=-1, data_range=dr, gaussian_weights=True, sigma=1.5,
            use_sample_covariance=False)),
        "delta_e_2000": float(np.mean(de)),
    }))


if __name__ == "__main__":
    main()
