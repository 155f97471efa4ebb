#!/usr/bin/env python3
"""Make (and read back) DNGs whose GainMap opcode is written by the Adobe DNG SDK (dngpy).

usage:
  make_gainmap_dng.py make IN.dng OUT.dng [--rows R] [--cols C] [--planes P]
                           [--spacing-v S] [--spacing-h S] [--origin-v O] [--origin-h O]
  make_gainmap_dng.py read FILE.dng

make: opens IN with the SDK (dngpy.Dng), sets a GainMap of R x C points x P planes whose
      gains are a deterministic radial falloff (1 at the centre, up to 2.6 in the corners,
      plus 0.01 per plane so planes differ), saves OUT through the SDK, and prints as JSON
      what it set: rows, cols, planes, spacing_v, spacing_h, origin_v, origin_h and gains
      (row-major, planes last, as float32 values).
      Spacing defaults: 1 / (R - 1) and 1 / (C - 1) (the map spans the image), origin 0.
read: prints the GainMap the SDK reads from FILE in the same JSON form (null when none).

The SDK writes it as the only opcode of OpcodeList2 (id 9, DNG 1.3.0.0, flags 0), with the
area set to the whole stored image, plane 0, planes = the map's planes, pitch 1x1.
"""
import argparse
import json
import sys

import numpy as np
import dngpy


def falloff(rows, cols, planes):
    v = np.linspace(-1.0, 1.0, rows) if rows > 1 else np.zeros(1)
    h = np.linspace(-1.0, 1.0, cols) if cols > 1 else np.zeros(1)
    r2 = (v[:, None] ** 2 + h[None, :] ** 2) / 2.0  # 0 at the centre, 1 in the corners
    g = 1.0 + 1.6 * r2
    gains = np.stack([g + 0.01 * p for p in range(planes)], axis=-1)
    return gains.astype(np.float32)


def as_json(gm):
    if gm is None:
        return None
    data = np.asarray(gm.to_numpy(), dtype=np.float32)
    return {
        "rows": int(gm.rows),
        "cols": int(gm.cols),
        "planes": int(gm.planes),
        "spacing_v": float(gm.spacing_v),
        "spacing_h": float(gm.spacing_h),
        "origin_v": float(gm.origin_v),
        "origin_h": float(gm.origin_h),
        "gains": [float(x) for x in data.reshape(-1)],
    }


def make(a):
    d = dngpy.Dng(a.input)
    gm = dngpy._native.DngGainMap()
    gm.rows, gm.cols, gm.planes = a.rows, a.cols, a.planes
    gm.spacing_v = a.spacing_v if a.spacing_v is not None else 1.0 / max(a.rows - 1, 1)
    gm.spacing_h = a.spacing_h if a.spacing_h is not None else 1.0 / max(a.cols - 1, 1)
    gm.origin_v, gm.origin_h = a.origin_v, a.origin_h
    gm.data = falloff(a.rows, a.cols, a.planes)
    d.set_gainmap(gm)
    d.save(a.output)
    # What the SDK itself reads back from the file it wrote.
    back = dngpy.Dng(a.output).get_gainmap()
    if back is None:
        print("the SDK wrote no GainMap", file=sys.stderr)
        return 1
    print(json.dumps(as_json(back)))
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("make")
    m.add_argument("input")
    m.add_argument("output")
    m.add_argument("--rows", type=int, default=5)
    m.add_argument("--cols", type=int, default=7)
    m.add_argument("--planes", type=int, default=1)
    m.add_argument("--spacing-v", type=float)
    m.add_argument("--spacing-h", type=float)
    m.add_argument("--origin-v", type=float, default=0.0)
    m.add_argument("--origin-h", type=float, default=0.0)
    r = sub.add_parser("read")
    r.add_argument("file")
    a = p.parse_args()
    if a.cmd == "make":
        return make(a)
    print(json.dumps(as_json(dngpy.Dng(a.file).get_gainmap())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
