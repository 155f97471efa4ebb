#!/usr/bin/env python3
"""Check that an EXR written by day2night's own encoder decodes, in both the OpenEXR Python
package and OpenImageIO, to exactly the sample values the writer intended.

usage: isp_exr_values.py FILE.exr EXPECTED.f32 half|float WIDTH HEIGHT COMPRESSION
EXPECTED.f32 holds WIDTH*HEIGHT*3 little-endian float32 values, interleaved RGB, row-major,
already rounded to the sample type (half values exactly representable). COMPRESSION is
OIIO's name (none, zip, zips). Prints a JSON line; exit 1 on any failed check.
"""
import json
import sys

import numpy as np
import OpenEXR
import OpenImageIO as oiio


def compare(who, got, want, fails):
    if got.shape != want.shape:
        fails.append(f"{who}: shape {got.shape}, want {want.shape}")
        return None
    bad = got.astype(np.float32) != want
    if bad.any():
        idx = np.argwhere(bad)[0]
        fails.append(f"{who}: {int(bad.sum())} samples differ, first at {idx.tolist()}: "
                     f"{got[tuple(idx)]!r} != {want[tuple(idx)]!r}")
    return int(bad.sum())


def main():
    path, exp, kind = sys.argv[1], sys.argv[2], sys.argv[3]
    w, h, comp = int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
    want = np.fromfile(exp, dtype="<f4").reshape(h, w, 3)
    dtype = np.float16 if kind == "half" else np.float32
    fails = []
    with OpenEXR.File(path, separate_channels=True) as f:
        ch = f.channels()
        if sorted(ch) != ["B", "G", "R"]:
            fails.append(f"OpenEXR channels {sorted(ch)}")
        else:
            for n in ch:
                if ch[n].pixels.dtype != dtype:
                    fails.append(f"OpenEXR channel {n} dtype {ch[n].pixels.dtype}")
            got = np.stack([ch["R"].pixels, ch["G"].pixels, ch["B"].pixels], axis=-1)
            compare("OpenEXR", got, want, fails)
        exr_comp = str(f.header().get("compression"))
        want_comp = {"none": "NO_COMPRESSION", "zips": "ZIPS_COMPRESSION",
                     "zip": "ZIP_COMPRESSION"}[comp]
        if want_comp not in exr_comp:
            fails.append(f"OpenEXR compression {exr_comp}, want {want_comp}")
    inp = oiio.ImageInput.open(path)
    oiio_comp = None
    if inp is None:
        fails.append(f"OpenImageIO cannot open: {oiio.geterror()}")
    else:
        spec = inp.spec()
        data = inp.read_image(oiio.HALF if kind == "half" else oiio.FLOAT)
        inp.close()
        oiio_comp = spec.getattribute("compression")
        if oiio_comp != comp:
            fails.append(f"OIIO compression {oiio_comp!r}, want {comp!r}")
        if str(spec.format) != kind:
            fails.append(f"OIIO format {spec.format}")
        if list(spec.channelnames) != ["R", "G", "B"]:
            fails.append(f"OIIO channels {list(spec.channelnames)}")
        if data is None:
            fails.append(f"OIIO read failed: {oiio.geterror()}")
        else:
            compare("OIIO", np.asarray(data), want, fails)
    print(json.dumps({"failures": fails, "samples": int(want.size),
                      "openexr_compression": exr_comp, "oiio_compression": oiio_comp}))
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
