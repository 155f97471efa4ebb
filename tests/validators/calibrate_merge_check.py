#!/usr/bin/env python3
"""Check a merged DNG against its frames with LibRaw (rawpy) and the Adobe DNG SDK (dngpy).

usage: calibrate_merge_check.py MERGED.dng FRAME.dng...
- rawpy opens every file; the merged image's normalized values (x - black) / (white - black)
  must equal the mean of the frames' normalized values within the output's rounding
  (0.5 DN of the output, i.e. 0.5 / K DN of the mean with K = white_out / white_in), and
  sites saturated in any frame must be at the output white level;
- dngpy (Adobe DNG SDK) must load the merged file with no "*** Error" / "*** Warning" on
  stderr beyond those the first frame itself triggers (a source without crop padding warns
  about it, and the merge keeps the source's geometry), and decode the same pixels as rawpy.
Exit 0 when all holds, 1 with the failures otherwise.
"""
import subprocess
import sys

import numpy as np
import rawpy


def levels(r):
    b = set(r.black_level_per_channel)
    if len(b) != 1:
        raise SystemExit(f"per-channel blacks differ: {r.black_level_per_channel}")
    return float(b.pop()), float(r.white_level)


def main():
    merged, frames = sys.argv[1], sys.argv[2:]
    fails = []
    with rawpy.imread(merged) as r:
        m = r.raw_image.astype(np.float64)
        bm, wm = levels(r)
    acc = None
    sat = None
    for f in frames:
        with rawpy.imread(f) as r:
            x = r.raw_image.astype(np.float64)
            b, w = levels(r)
        y = (x - b) / (w - b)
        acc = y if acc is None else acc + y
        s = x >= w
        sat = s if sat is None else (sat | s)
    mean = acc / len(frames)
    k = wm / w
    ym = (m - bm) / (wm - bm)
    tol = 0.5 / (k * (w - b)) + 1e-9
    ok = ~sat
    err = np.abs(ym - mean)[ok]
    if err.size and err.max() > tol:
        i = int(np.argmax(err))
        fails.append(f"merged differs from the frames' mean by {err.max():.3e} (tolerance {tol:.3e}) at unsaturated site #{i}")
    if np.any(m[sat] != wm):
        fails.append(f"{int(np.count_nonzero(m[sat] != wm))} sites saturated in a frame are not at white {wm}")
    code = (
        "import sys, dngpy, numpy as np\n"
        "d = dngpy.Dng(sys.argv[1])\n"
        "np.save(sys.argv[2], np.asarray(d.raw_pixels))\n"
    )
    npy = merged + ".sdk.npy"

    def complaints(path, out):
        p = subprocess.run([sys.executable, "-c", code, path, out], capture_output=True, text=True)
        return p, {l.strip() for l in (p.stdout + p.stderr).splitlines() if "***" in l}

    _, inherited = complaints(frames[0], merged + ".first.npy")
    p, found = complaints(merged, npy)
    bad = sorted(found - inherited)
    if p.returncode != 0:
        fails.append(f"dngpy failed to load: {p.stderr.strip()[-500:]}")
    elif bad:
        fails.append("DNG SDK complaints: " + "; ".join(bad))
    else:
        sdk = np.load(npy).astype(np.float64).reshape(-1)
        with rawpy.imread(merged) as r:
            vis = r.raw_image_visible.astype(np.float64).reshape(-1)
            full = r.raw_image.astype(np.float64).reshape(-1)
        if not (np.array_equal(sdk, full) or np.array_equal(sdk, vis)):
            fails.append(f"DNG SDK pixels differ from rawpy ({sdk.size} vs {full.size} samples)")
    if fails:
        print("\n".join(fails))
        sys.exit(1)
    print(f"ok: {len(frames)} frames, K={k:g}, max error {err.max() if err.size else 0:.3e} <= {tol:.3e}; rawpy and DNG SDK accept it")


if __name__ == "__main__":
    main()
