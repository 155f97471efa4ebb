#!/usr/bin/env python3
"""Write scikit-image's bundled colour sample photos as 16-bit RGB PNGs (8-bit values
times 257) for the demosaic accuracy measurement.

usage: isp_skimage_photos.py OUT_DIR
Prints one line per written file: NAME WIDTH HEIGHT.
"""
import os
import sys

import numpy as np
import OpenImageIO as oiio
from skimage import data

NAMES = ["astronaut", "coffee", "chelsea", "rocket", "immunohistochemistry"]


def main():
    out = sys.argv[1]
    for name in NAMES:
        try:
            img = getattr(data, name)()
        except Exception as e:  # not bundled in this scikit-image
            print(f"# skip {name}: {e}", file=sys.stderr)
            continue
        img = np.asarray(img)
        if img.ndim != 3 or img.shape[2] < 3:
            continue
        img16 = img[..., :3].astype(np.uint16) * 257
        path = os.path.join(out, f"{name}.png")
        # PIL cannot write 16-bit RGB PNGs; OpenImageIO can
        out_img = oiio.ImageOutput.create(path)
        spec = oiio.ImageSpec(img16.shape[1], img16.shape[0], 3, oiio.UINT16)
        if out_img is None or not out_img.open(path, spec):
            raise SystemExit(f"cannot write {path}: {oiio.geterror()}")
        out_img.write_image(np.ascontiguousarray(img16))
        out_img.close()
        print(name, img.shape[1], img.shape[0])


if __name__ == "__main__":
    main()
