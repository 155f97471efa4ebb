#!/usr/bin/env python3
"""Write the opcode-path benchmark inputs of issue 26 (docs/benchmarks.md, "DNG opcodes:
work and memory") with tifffile + imagecodecs and the day2night wheel (lossless JPEG XL tiles, as the issue's files).

usage: make_opcode_inputs.py OUT_DIR [--size WxH]

  plain96.dng     16-bit RGGB, 12000 x 8000 (96 MP), a smooth scene, no opcode
  warp96.dng      the same with one identity WarpRectilinear in OpcodeList3
  realwarp96.dng  the same with one WarpRectilinear of kr1 = -0.02 (a real distortion)
  warp2_96.dng    the same with one WarpRectilinear2 (kr1 = 0.01, kr2 = -0.03)
  fisheye96.dng   the same with one WarpFisheye (kr1 = -0.05)
  realwarp96o6.dng  realwarp96.dng with Orientation 6 (bands are columns)
  warps4096.dng   2048 x 1536 with 4096 identity WarpRectilinear in OpcodeList3 (~350 KB)
  realwarps4096.dng  the same with kr1 = 0.01: over the opcode work budget
  fix4096.dng     512 x 384 with 4096 FixBadPixelsConstant (constant 0) in OpcodeList1

--size changes the 96 MP frames' size (e.g. 4000x3000 for a quick run).
"""
import argparse
import os
import struct

import numpy as np
import tifffile
# XYZ (D65) -> linear sRGB, the library's tabulated matrix (day2night::color::xyz): the
# ColorMatrix1 of the inputs. The venv of scripts/test.sh has the day2night wheel.
from day2night._native import XYZ_TO_SRGB


def opcode(op_id, params):
    return struct.pack(">I4BII", op_id, 1, 3, 0, 0, 0, len(params)) + params


def warp(k1):
    params = struct.pack(">I", 1) + struct.pack(">6d", 1.0, k1, 0.0, 0.0, 0.0, 0.0)
    return opcode(1, params + struct.pack(">2d", 0.5, 0.5))


def warp2(k1, k2):
    kr = [1.0, k1, k2] + [0.0] * 12
    params = struct.pack(">I", 1) + struct.pack(">19d", *kr, 0.0, 0.0, 0.0, 1.0)
    return opcode(14, params + struct.pack(">2dI", 0.5, 0.5, 0))


def fisheye(k1):
    params = struct.pack(">I", 1) + struct.pack(">4d", 1.0, k1, 0.0, 0.0)
    return opcode(2, params + struct.pack(">2d", 0.5, 0.5))


def fix_constant(constant):
    return opcode(4, struct.pack(">II", constant, 0))


def op_list(ops):
    return struct.pack(">I", len(ops)) + b"".join(ops)


def srational(vals):
    out = []
    for v in vals:
        out += [int(round(v * 10000)), 10000]
    return out


def tags(w, h, lists, orientation=1):
    cm = [v for row in XYZ_TO_SRGB for v in row]
    t = [
        (50706, "B", 4, (1, 7, 0, 0), True),  # DNGVersion
        (50707, "B", 4, (1, 4, 0, 0), True),  # DNGBackwardVersion
        (271, "s", 0, "day2night", True),
        (272, "s", 0, "opcode bench", True),
        (50708, "s", 0, "day2night opcode bench", True),
        (50714, "H", 1, (1024,), True),  # BlackLevel
        (50717, "H", 1, (65535,), True),  # WhiteLevel
        (50721, "2i", 9, tuple(srational(cm)), True),  # ColorMatrix1
        (50778, "H", 1, (21,), True),  # CalibrationIlluminant1 D65
        (50728, "2I", 3, tuple(srational([0.55, 1.0, 0.7])), True),  # AsShotNeutral
        (274, "H", 1, (orientation,), True),  # Orientation
        (50829, "I", 4, (0, 0, h, w), True),  # ActiveArea
        (33421, "H", 2, (2, 2), True),  # CFARepeatPatternDim
        (33422, "B", 4, (0, 1, 1, 2), True),  # CFAPattern RGGB
        (50710, "B", 3, (0, 1, 2), True),  # CFAPlaneColor
        (50711, "H", 1, (1,), True),  # CFALayout
    ]
    for n, data in lists.items():
        t.append(({1: 51008, 2: 51009, 3: 51022}[n], "B", len(data), data, True))
    return t


def scene(w, h):
    """Flat steps (every 256 columns and rows) per CFA colour: compresses to almost
    nothing, like the issue's 59 KB file."""
    y = (np.arange(h) // 256 % 16).astype(np.uint16)[:, None]
    x = (np.arange(w) // 256 % 16).astype(np.uint16)[None, :]
    a = np.empty((h, w), np.uint16)
    for r0 in range(0, h, 512):
        a[r0:r0 + 512] = 4000 + 1500 * y[r0:r0 + 512] + 900 * x
    a[0::2, 1::2] //= 2
    return a


def write(path, data, lists, orientation=1):
    h, w = data.shape
    tifffile.imwrite(path, data, photometric=32803, compression=52546,
                     compressionargs=dict(lossless=True, effort=3), tile=(512, 512),
                     extratags=tags(w, h, lists, orientation), subfiletype=0, planarconfig="contig")
    print(f"{path}: {w}x{h}, {os.path.getsize(path)} bytes")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--size", default="12000x8000")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    w, h = (int(v) for v in a.size.split("x"))
    big = scene(w, h)
    write(os.path.join(a.out, "plain96.dng"), big, {})
    write(os.path.join(a.out, "warp96.dng"), big, {3: op_list([warp(0.0)])})
    write(os.path.join(a.out, "realwarp96.dng"), big, {3: op_list([warp(-0.02)])})
    write(os.path.join(a.out, "warp2_96.dng"), big, {3: op_list([warp2(0.01, -0.03)])})
    write(os.path.join(a.out, "fisheye96.dng"), big, {3: op_list([fisheye(-0.05)])})
    write(os.path.join(a.out, "realwarp96o6.dng"), big, {3: op_list([warp(-0.02)])}, 6)
    del big
    mid = scene(2048, 1536)
    write(os.path.join(a.out, "warps4096.dng"), mid, {3: op_list([warp(0.0)] * 4096)})
    write(os.path.join(a.out, "realwarps4096.dng"), mid, {3: op_list([warp(0.01)] * 4096)})
    small = scene(512, 384)
    small[100:104, 200:203] = 0
    write(os.path.join(a.out, "fix4096.dng"), small, {1: op_list([fix_constant(0)] * 4096)})


if __name__ == "__main__":
    main()
