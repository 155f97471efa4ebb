"""Decode a PNG written by day2night's own encoder (src/png_rows.rs) with two independent
readers and compare with the expected 8-bit RGB samples.

usage: png_rows.py FILE.png EXPECTED.rgb8 WIDTH HEIGHT TONE
Prints a JSON summary; exits 1 on any mismatch.
"""
import json
import sys

import numpy as np
import OpenImageIO as oiio
import skimage.io


def main():
    path, expected, w, h, tone = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
    want = np.fromfile(expected, dtype=np.uint8).reshape(h, w, 3)
    failures = []
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        failures.append("oiio: " + buf.geterror())
    else:
        spec = buf.spec()
        if (spec.width, spec.height, spec.nchannels) != (w, h, 3):
            failures.append(f"oiio size {spec.width}x{spec.height}x{spec.nchannels}")
        elif spec.format != oiio.UINT8:
            failures.append(f"oiio format {spec.format}")
        else:
            px = buf.get_pixels(oiio.UINT8)
            if not np.array_equal(px, want):
                failures.append(f"oiio pixels differ at {int((px != want).sum())} samples")
        cs = spec.get_string_attribute("oiio:ColorSpace")
        gamma = spec.get_float_attribute("oiio:Gamma", 0.0)
        if tone == "srgb" and "srgb" not in cs.lower():
            failures.append(f"oiio colour space {cs!r} for an sRGB file")
        if tone == "gamma22" and abs(gamma - 2.2) > 0.01:
            failures.append(f"oiio gamma {gamma} for a gamma 2.2 file")
    sk = skimage.io.imread(path)
    if sk.shape != (h, w, 3) or sk.dtype != np.uint8:
        failures.append(f"skimage shape {sk.shape} {sk.dtype}")
    elif not np.array_equal(sk, want):
        failures.append(f"skimage pixels differ at {int((sk != want).sum())} samples")
    print(json.dumps({"failures": failures, "samples": int(want.size)}))
    sys.exit(1 if failures else 0)


main()
