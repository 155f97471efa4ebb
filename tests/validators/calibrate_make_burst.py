#!/usr/bin/env python3
"""Independent burst generator for the noise-calibration closed loop (no day2night code).

usage: calibrate_make_burst.py OUTDIR --iso ISO --s S --o O [--frames N] [--width W]
                               [--height H] [--seed K] [--black B] [--white W]
Writes OUTDIR/frame_00.dng ... with tifffile: a minimal uncompressed CFA DNG (RGGB, 16-bit
container, BlackLevel/WhiteLevel, ISO in the TIFF/EP ISOSpeedRatings tag of IFD0). The scene
is a horizontal ramp y = 0.9 t^2 (dark-heavy, like a night scene) plus a little texture; each
frame adds N(0, S*y + O) in normalized units, rounds and clips to [0, white]. Prints the
truth as JSON on stdout: {"iso", "S", "O", "black", "white", "frames", "files"}.
"""
import argparse
import json
import os

import numpy as np
import tifffile


def write_dng(path, data, black, white, iso):
    h, w = data.shape
    cm = [(int(round(v * 10000)), 10000) for v in
          (3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108, 0.0415560, 0.0556434, -0.2040259, 1.0572252)]
    extratags = [
        (271, "s", 0, "day2night", True),  # Make
        (272, "s", 0, "PythonBurst", True),  # Model
        (33421, "H", 2, (2, 2), True),  # CFARepeatPatternDim
        (33422, "B", 4, (0, 1, 1, 2), True),  # CFAPattern RGGB
        (34855, "H", 1, (iso,), True),  # ISOSpeedRatings (TIFF/EP, IFD0)
        (50706, "B", 4, (1, 4, 0, 0), True),  # DNGVersion
        (50707, "B", 4, (1, 1, 0, 0), True),  # DNGBackwardVersion
        (50708, "s", 0, "day2night python burst", True),  # UniqueCameraModel
        (50714, "I", 1, (int(black),), True),  # BlackLevel
        (50717, "I", 1, (int(white),), True),  # WhiteLevel
        (50721, "2i", 9, tuple(x for p in cm for x in p), True),  # ColorMatrix1 (SRATIONAL)
        (50728, "2I", 3, (1, 2, 1, 1, 3, 5), True),  # AsShotNeutral 0.5 1 0.6
        (50778, "H", 1, (21,), True),  # CalibrationIlluminant1 = D65
    ]
    tifffile.imwrite(
        path,
        data.astype("<u2"),
        photometric=32803,  # CFA
        compression=None,
        subfiletype=0,
        software="calibrate_make_burst.py",
        extratags=extratags,
        metadata=None,
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--iso", type=int, required=True)
    ap.add_argument("--s", type=float, required=True)
    ap.add_argument("--o", type=float, required=True)
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--width", type=int, default=1024)
    ap.add_argument("--height", type=int, default=512)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--black", type=float, default=64)
    ap.add_argument("--white", type=float, default=1023)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    scale = a.white - a.black
    t = np.tile(np.arange(a.width) / a.width, (a.height, 1))
    clean = np.round((0.9 * t * t + 0.01 * rng.random((a.height, a.width))) * scale + a.black)
    y = (clean - a.black) / scale
    sd = np.sqrt(np.maximum(a.s * y + a.o, 0.0)) * scale
    os.makedirs(a.outdir, exist_ok=True)
    files = []
    for k in range(a.frames):
        x = np.clip(np.round(clean + rng.normal(0.0, 1.0, clean.shape) * sd), 0, a.white)
        p = os.path.join(a.outdir, f"frame_{k:02d}.dng")
        write_dng(p, x, a.black, a.white, a.iso)
        files.append(p)
    print(json.dumps({"iso": a.iso, "S": a.s, "O": a.o, "black": a.black, "white": a.white,
                      "frames": a.frames, "files": files}))


if __name__ == "__main__":
    main()
