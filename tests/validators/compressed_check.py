#!/usr/bin/env python3
"""Independent readers on the files of make_compressed_dngs.py (JPEG XL and lossy JPEG DNGs).

usage: compressed_check.py DIR NAME [NAME ...]

For every NAME (DIR/NAME.dng with its expected samples DIR/NAME.bin, see the generator):
  dngpy (Adobe DNG SDK) : opens it with no `*** Error` / `*** Warning` line; its stage-1
                          raw pixels equal NAME.bin exactly (JPEG XL) or within 1 code (lossy
                          JPEG: the SDK's libjpeg and libjpeg-turbo round apart by one).
  rawpy (LibRaw)        : where LibRaw reads the file, its raw_image equals NAME.bin on the
                          ActiveArea (same tolerances). KNOWN, not failures: LibRaw builds
                          without JPEG XL refuse JPEG XL DNGs; LibRaw's raw_image of a
                          LinearRaw file is not the stored samples (only its shape is checked).
Prints one line per check; exits 1 if any check failed.
"""
import json
import os
import subprocess
import sys

import numpy as np

FAILS = []


def fail(msg):
    FAILS.append(msg)
    print("FAIL", msg)


def ok(msg):
    print("ok  ", msg)


SDK = (
    "import dngpy, sys, numpy as np\n"
    "d = dngpy.Dng(sys.argv[1])\n"
    "np.save(sys.argv[2], np.asarray(d.raw_pixels))\n"
)


def main():
    d = sys.argv[1]
    for name in sys.argv[2:]:
        path = os.path.join(d, name + ".dng")
        lossy = ("jpeg" in name and "jxl" not in name) or "lossy" in name
        tol = 1 if lossy else 0
        import tifffile

        page = tifffile.TiffFile(path).pages[0]
        shape = page.shape
        exp = np.fromfile(os.path.join(d, name + ".bin"), "<u2").astype(np.int64).reshape(shape)
        npy = os.path.join(d, name + ".sdk.npy")
        r = subprocess.run([sys.executable, "-c", SDK, path, npy], capture_output=True, text=True)
        msgs = [l.strip() for l in (r.stdout + r.stderr).splitlines() if "***" in l]
        if r.returncode != 0:
            fail(f"{name}: the DNG SDK cannot read it: {r.stderr.strip()[-300:]}")
        elif msgs:
            fail(f"{name}: the DNG SDK says {msgs}")
        else:
            px = np.load(npy).astype(np.int64).reshape(shape)
            diff = int(np.abs(px - exp).max())
            if diff > tol:
                fail(f"{name}: SDK pixels differ from the expected by up to {diff} (tolerance {tol})")
            else:
                ok(f"{name}: SDK reads it, no warning, pixels within {diff} of the expected")
        try:
            import rawpy

            with rawpy.imread(path) as rp:
                ri = rp.raw_image.astype(np.int64)
        except Exception as e:  # LibRaw without JPEG XL support
            print("KNOWN", f"{name}: LibRaw does not read it ({e})")
            continue
        t, l, b, rr = 2, 4, shape[0] - 2, shape[1] - 4  # the generator's ActiveArea
        region = exp[t:b, l:rr]
        got = ri[: region.shape[0], : region.shape[1]]
        if region.ndim == 3:
            got = got[..., : region.shape[2]]
        if got.shape != region.shape:
            print("KNOWN", f"{name}: LibRaw raw_image {ri.shape} is not the active area {region.shape}")
            continue
        if region.ndim == 3:
            # LibRaw's raw_image of a LinearRaw DNG is not the stored samples (it goes
            # through LibRaw's own curve and scaling: 8-bit 255 became 10219 in 0.21).
            print("KNOWN", f"{name}: LibRaw reads it ({ri.shape}), values not comparable")
            continue
        diff = int(np.abs(got - region).max())
        if diff > tol:
            fail(f"{name}: LibRaw raw_image differs by up to {diff} (tolerance {tol})")
        else:
            ok(f"{name}: LibRaw raw_image within {diff} of the expected")
    print(json.dumps({"failures": len(FAILS)}))
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
