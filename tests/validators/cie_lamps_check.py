#!/usr/bin/env python3
"""Check day2night's embedded CIE 015:2018 lamp table, CCT/Duv and Planckian locus against
colour-science.

usage: cie_lamps_check.py LAMPS.json
LAMPS.json (written by the test): {"lamps": [{"name", "xy", "cct", "duv"}, ...],
"locus": [[T, x, y], ...], "points": [{"xy", "cct", "duv"}, ...]}.
- every lamp's xy equals colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"][name]
  (abs 1e-12: the same published digits);
- day2night's CCT and Duv of each lamp and point agree with Ohno 2013
  (colour.temperature.uv_to_CCT_Ohno2013): CCT within 1 mired, Duv within 2e-4;
- the locus points (Krystek's approximation) have Ohno CCT within 0.5 mired of T and
  |Duv| < 2e-4.
Exit 0 when all agree, 1 with the differences otherwise.
"""
import json
import sys
import warnings

warnings.filterwarnings("ignore")
import colour  # noqa: E402
import numpy as np  # noqa: E402


def ohno(xy):
    cct, duv = colour.temperature.uv_to_CCT_Ohno2013(colour.xy_to_UCS_uv(np.array(xy)))
    return float(cct), float(duv)


def main():
    doc = json.load(open(sys.argv[1]))
    ccs = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]
    fails = []
    names = {lamp["name"] for lamp in doc["lamps"]}
    want = (
        {"A"}
        | {f"HP{i}" for i in range(1, 6)}
        | {f"LED-B{i}" for i in range(1, 6)}
        | {"LED-BH1", "LED-RGB1", "LED-V1", "LED-V2"}
        | {f"FL{i}" for i in range(1, 13)}
        | {f"FL3.{i}" for i in range(1, 16)}
    )
    if names != want:
        fails.append(f"lamp names differ: missing {sorted(want - names)}, extra {sorted(names - want)}")
    worst = [0.0, 0.0]
    for lamp in doc["lamps"]:
        name, xy = lamp["name"], lamp["xy"]
        if name not in ccs:
            continue
        ref = ccs[name]
        if abs(ref[0] - xy[0]) > 1e-12 or abs(ref[1] - xy[1]) > 1e-12:
            fails.append(f"{name}: xy {xy} vs colour-science {list(ref)}")
        doc.setdefault("points", []).append(lamp)
    for p in doc.get("points", []):
        cct, duv = ohno(p["xy"])
        dc, dd = abs(1e6 / p["cct"] - 1e6 / cct), abs(p["duv"] - duv)
        worst = [max(worst[0], dc), max(worst[1], dd)]
        if dc > 1.0 or dd > 2e-4:
            fails.append(f"{p.get('name', p['xy'])}: CCT {p['cct']:.1f} Duv {p['duv']:+.5f} vs Ohno {cct:.1f} {duv:+.5f}")
    for t, x, y in doc["locus"]:
        cct, duv = ohno([x, y])
        worst = [worst[0], max(worst[1], abs(duv))]
        if abs(1e6 / cct - 1e6 / t) > 0.5 or abs(duv) > 2e-4:
            fails.append(f"locus {t} K: Ohno CCT {cct:.1f}, Duv {duv:+.6f}")
    print(f"{len(doc['lamps'])} lamps, {len(doc['points'])} points, {len(doc['locus'])} locus points; "
          f"worst CCT {worst[0]:.3f} mired, Duv {worst[1]:.2e}")
    if fails:
        print("\n".join(fails))
        sys.exit(1)


if __name__ == "__main__":
    main()
