#!/usr/bin/env python3
"""Compare day2night's decoded raw with LibRaw (rawpy) on the same DNG.

usage: read_compare.py FILE.dng PIXELS.u16 EXPECT.json
  PIXELS.u16   day2night's stored samples, little-endian u16, row-major
  EXPECT.json  {"width", "height", "active_area": [t,l,b,r] | null, "bayer": "RGGB",
                "black": float | null, "white": float | null, "neutral": [r, g, b] | null,
                "linearization": [table] | null}
  With a LinearizationTable LibRaw's raw_image holds table[stored], so that is compared.
Exit 0 when everything matches exactly (pixels) or within 1e-4 (white balance); otherwise
print every mismatch and exit 1.
"""
import json
import sys

import numpy as np
import rawpy


def main():
    dng, pix, exp = sys.argv[1:4]
    e = json.load(open(exp))
    fails = []
    with rawpy.imread(dng) as r:
        raw = r.raw_image.copy()
        h, w = raw.shape
        if (w, h) != (e["width"], e["height"]):
            fails.append(f"size: rawpy {w}x{h}, day2night {e['width']}x{e['height']}")
        ours = np.fromfile(pix, dtype="<u2")
        if ours.size != e["width"] * e["height"]:
            fails.append(f"pixel file holds {ours.size} samples")
        elif not fails:
            ours = ours.reshape(h, w)
            if e.get("linearization"):
                t = np.array(e["linearization"], dtype=np.uint16)
                ours = t[np.minimum(ours, len(t) - 1)]
            diff = np.count_nonzero(ours != raw)
            if diff:
                y, x = np.argwhere(ours != raw)[0]
                fails.append(
                    f"{diff} samples differ; first at row {y} col {x}: rawpy {raw[y, x]}, day2night {ours[y, x]}"
                )
        s = r.sizes
        if e.get("active_area"):
            t, l, b, rr = e["active_area"]
            if (s.top_margin, s.left_margin, s.height, s.width) != (t, l, b - t, rr - l):
                fails.append(f"active area: rawpy {s}, day2night {e['active_area']}")
        desc = r.color_desc.decode()
        pat = r.raw_pattern
        name = "".join(desc[pat[i][j]] for i in range(2) for j in range(2)).replace("G", "G")
        # LibRaw numbers the second green 3 ("RGBG"): map both greens to G.
        if name != e["bayer"]:
            fails.append(f"CFA: rawpy {name}, day2night {e['bayer']}")
        blacks = set(r.black_level_per_channel)
        if e.get("black") is not None and blacks != {e["black"]}:
            fails.append(f"black: rawpy {r.black_level_per_channel}, day2night {e['black']}")
        if e.get("white") is not None and r.white_level != e["white"]:
            fails.append(f"white: rawpy {r.white_level}, day2night {e['white']}")
        if e.get("neutral"):
            wb = np.array(r.camera_whitebalance[:3], dtype=float)
            wb = wb / wb[1]
            inv = 1.0 / np.array(e["neutral"], dtype=float)
            if not np.allclose(wb, inv, rtol=1e-4):
                fails.append(f"white balance: rawpy {wb.tolist()}, day2night 1/neutral {inv.tolist()}")
    if fails:
        print("\n".join(fails))
        sys.exit(1)
    print("OK: pixels, size, active area, CFA, levels, white balance match LibRaw")


if __name__ == "__main__":
    main()
