#!/usr/bin/env python3
"""Check an EXR written by day2night with two independent readers (the OpenEXR Python
package and OpenImageIO): R, G, B channels of the expected type (half|float), the
Rec.709/D65 chromaticities, the day2night attributes, finite values, size.

usage: isp_exr.py FILE.exr half|float WIDTH HEIGHT [KEY=VALUE ...]
Prints a JSON line; exit 1 on any failed check (listed under "failures").
"""
import json
import sys

import numpy as np
import OpenEXR
import OpenImageIO as oiio


def main():
    path, kind, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    want_attrs = dict(a.split("=", 1) for a in sys.argv[5:])
    fails = []
    # OpenEXR
    with OpenEXR.File(path, separate_channels=True) as f:
        hdr = f.header()
        ch = f.channels()
        names = sorted(ch.keys())
        if names != ["B", "G", "R"]:
            fails.append(f"OpenEXR channels {names}")
        want_dtype = np.float16 if kind == "half" else np.float32
        for n in names:
            px = ch[n].pixels
            if px.dtype != want_dtype:
                fails.append(f"channel {n} dtype {px.dtype}")
            if px.shape != (h, w):
                fails.append(f"channel {n} shape {px.shape}")
            if not np.isfinite(px.astype(np.float64)).all():
                fails.append(f"channel {n} has NaN/Inf")
        chroma = hdr.get("chromaticities")
        want = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)
        if chroma is None or not np.allclose(np.array(chroma, dtype=float), want, atol=1e-6):
            fails.append(f"chromaticities {chroma}")
        for k, v in want_attrs.items():
            got = hdr.get(k)
            if isinstance(got, bytes):
                got = got.decode()
            if got != v:
                fails.append(f"OpenEXR attribute {k} = {got!r}, want {v!r}")
        compression = str(hdr.get("compression"))
    # OpenImageIO
    inp = oiio.ImageInput.open(path)
    if inp is None:
        fails.append(f"OpenImageIO cannot open: {oiio.geterror()}")
        oi = {}
    else:
        spec = inp.spec()
        data = inp.read_image(oiio.FLOAT)
        inp.close()
        if (spec.width, spec.height, spec.nchannels) != (w, h, 3):
            fails.append(f"OIIO size {spec.width}x{spec.height}x{spec.nchannels}")
        if list(spec.channelnames) != ["R", "G", "B"]:
            fails.append(f"OIIO channels {list(spec.channelnames)}")
        fmt = str(spec.format)
        if fmt != kind:
            fails.append(f"OIIO format {fmt}")
        if data is None or not np.isfinite(data).all():
            fails.append("OIIO pixels not finite")
        for k, v in want_attrs.items():
            got = spec.getattribute(k)
            if got != v:
                fails.append(f"OIIO attribute {k} = {got!r}, want {v!r}")
        oi = {"format": fmt, "compression": spec.getattribute("compression"),
              "chromaticities": spec.getattribute("chromaticities")}
        if oi["chromaticities"] is not None and not np.allclose(
                np.array(oi["chromaticities"], dtype=float), want, atol=1e-6):
            fails.append(f"OIIO chromaticities {oi['chromaticities']}")
    print(json.dumps({"failures": fails, "compression": compression, "oiio": oi}, default=str))
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
