#!/usr/bin/env python3
"""GPS IFD of DNGs written by day2night, read by independent readers.

usage: dng_gps.py FILE.dng LAT LON ALT

tifffile : IFD0 has a GPSTag whose GPSLatitude/GPSLongitude/GPSAltitude (with their Ref
           tags) decode to LAT, LON, ALT (decimal degrees / metres, 1e-6).
exiftool : (required) `exiftool -n -GPSLatitude -GPSLongitude -GPSAltitude` gives the
           same numbers.
Prints one line per check; exits 1 if any check failed.
"""
import json
import shutil
import subprocess
import sys

import tifffile


def dms(v):
    # tifffile gives rationals as flat (num, den, num, den, ...) tuples
    vals = [v[i] / v[i + 1] for i in range(0, len(v), 2)]
    return vals[0] + vals[1] / 60 + vals[2] / 3600


def main():
    path, lat, lon, alt = sys.argv[1], *map(float, sys.argv[2:5])
    ok = True
    with tifffile.TiffFile(path) as t:
        tag = t.pages[0].tags.get("GPSTag")
        if tag is None:
            print("FAIL tifffile: no GPSTag in IFD0")
            return 1
        g = tag.value
        got_lat = dms(g["GPSLatitude"]) * (-1 if g["GPSLatitudeRef"] == "S" else 1)
        got_lon = dms(g["GPSLongitude"]) * (-1 if g["GPSLongitudeRef"] == "W" else 1)
        a = g["GPSAltitude"]
        got_alt = a[0] / a[1]
        good = abs(got_lat - lat) < 1e-6 and abs(got_lon - lon) < 1e-6 and abs(got_alt - alt) < 1e-6
        print(("OK" if good else "FAIL") + f" tifffile: {got_lat} {got_lon} {got_alt}")
        ok &= good
    exiftool = shutil.which("exiftool")
    if exiftool:
        out = subprocess.run(
            [exiftool, "-j", "-n", "-GPSLatitude", "-GPSLongitude", "-GPSAltitude", path],
            capture_output=True, text=True, check=True,
        ).stdout
        e = json.loads(out)[0]
        good = (
            abs(e.get("GPSLatitude", 1e9) - lat) < 1e-6
            and abs(e.get("GPSLongitude", 1e9) - lon) < 1e-6
            and abs(e.get("GPSAltitude", 1e9) - alt) < 1e-6
        )
        print(("OK" if good else "FAIL") + f" exiftool: {e}")
        ok &= good
    else:
        # tests/it/dng_gps.rs requires exiftool (or is ignored when it is declared absent)
        print("FAIL exiftool: not on PATH (Debian libimage-exiftool-perl)")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
