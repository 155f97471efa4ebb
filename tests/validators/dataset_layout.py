#!/usr/bin/env python3
"""Walk a day2night dataset the way a PyTorch Dataset would (see docs/dataset.md) and check
it with independent readers: every manifest record's files exist with the recorded size and
SHA-256; clean and noisy DNGs open in LibRaw (rawpy) with the same raw size, and the noisy
ones differ from the clean one; EXR targets open in OpenEXR with R, G, B channels and finite
values; sidecars parse and name the record's ISOs; every file of the layout is listed.

usage: dataset_layout.py OUT_DIR EXPECTED_OK_UNITS
Exit 0 when everything holds, else print every problem and exit 1.
"""
import glob
import hashlib
import json
import os
import sys

import numpy as np
import OpenEXR
import rawpy


def records(out):
    recs = {}
    for m in sorted(glob.glob(os.path.join(out, "manifest*.jsonl"))):
        with open(m) as f:
            for line in f:
                line = line.strip()
                if line:
                    r = json.loads(line)
                    recs[(r["input"], r["variant"])] = r
    return list(recs.values())


def main():
    out, expected = sys.argv[1], int(sys.argv[2])
    fails = []
    recs = records(out)
    ok = [r for r in recs if r["status"] == "ok"]
    if len(ok) != expected:
        fails.append(f"{len(ok)} ok records, expected {expected}")
    listed = set()
    for r in ok:
        by_kind = {}
        for o in r["outputs"]:
            p = os.path.join(out, o["path"])
            listed.add(os.path.normpath(p))
            if not os.path.isfile(p):
                fails.append(f"{o['path']}: missing")
                continue
            data = open(p, "rb").read()
            if len(data) != o["bytes"] or hashlib.sha256(data).hexdigest() != o["sha256"]:
                fails.append(f"{o['path']}: size or SHA-256 differs from the manifest")
            if not o["path"].startswith(r["split"] + "/" + o["kind"] + "/"):
                fails.append(f"{o['path']}: not under {r['split']}/{o['kind']}/")
            by_kind.setdefault(o["kind"], []).append(p)
        clean = by_kind.get("clean_raw", [])
        if len(clean) != 1:
            fails.append(f"{r['input']}: {len(clean)} clean raws")
            continue
        with rawpy.imread(clean[0]) as c:
            craw = c.raw_image.copy()
        noisy = by_kind.get("noisy_raw", [])
        if len(noisy) != len(r["iso"]):
            fails.append(f"{r['input']}: {len(noisy)} noisy raws for ISOs {r['iso']}")
        for n in noisy:
            with rawpy.imread(n) as nr:
                nraw = nr.raw_image.copy()
            if nraw.shape != craw.shape:
                fails.append(f"{n}: raw shape {nraw.shape} != clean {craw.shape}")
            elif np.array_equal(nraw, craw):
                fails.append(f"{n}: identical to the clean raw (no noise)")
        for t in by_kind.get("target", []):
            if t.endswith(".exr"):
                f = OpenEXR.File(t)
                ch = f.channels()
                names = set(ch.keys())
                if "RGB" in names:
                    px = np.asarray(ch["RGB"].pixels, dtype=np.float32)
                elif {"R", "G", "B"} <= names:
                    px = np.stack([np.asarray(ch[k].pixels, dtype=np.float32) for k in "RGB"], -1)
                else:
                    fails.append(f"{t}: channels {sorted(names)}")
                    continue
                if not np.isfinite(px).all() or px.size == 0:
                    fails.append(f"{t}: empty or non-finite pixels")
        metas = by_kind.get("meta", [])
        if len(metas) != 1:
            fails.append(f"{r['input']}: {len(metas)} sidecars")
        else:
            sc = json.load(open(metas[0]))
            isos = [n["iso"] for n in sc["plan"]["noise"]]
            if isos != r["iso"]:
                fails.append(f"{metas[0]}: ISOs {isos} != manifest {r['iso']}")
            if sc["input"]["sha256"] != r["input_sha256"]:
                fails.append(f"{metas[0]}: input SHA-256 differs from the manifest")
    for split in ("train", "val"):
        for p in glob.glob(os.path.join(out, split, "*", "*")):
            if os.path.normpath(p) not in listed:
                fails.append(f"{p}: on disk but in no ok record")
    for f in fails:
        print(f)
    print(f"{len(ok)} ok records, {len(listed)} files checked, {len(fails)} problems")
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
