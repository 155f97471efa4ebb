#!/usr/bin/env python3
"""Independent checks of the DNGs written by `day2night synth`, against its sidecar and the
day DNG they were made from.

usage: synth_check.py SOURCE.dng SIDECAR.json OUTDIR

For every DNG listed in the sidecar's outputs:
  rawpy (LibRaw) : opens it (unless LibRaw refuses the SOURCE too); raw_pattern and
                   white_level equal the SOURCE's; camera_whitebalance (green-normalised)
                   equals 1 / the sidecar's night neutral within 1e-5 relative; raw values
                   never exceed the white level; noisy files differ from the clean one with
                   a mean difference near 0 (|mean| < 0.05 std) where the clean raw is below 0.8 white.
  dngpy (SDK)    : opens it; no `*** Error` / `*** Warning` line the SOURCE did not produce;
                   its white balance equals the sidecar's night neutral within 1e-5.
  tifffile       : Exif ISOSpeedRatings = the clean ISO (clean) or the file's ISO (noisy);
                   NoiseProfile = the plan's model averaged per colour plane (rel. 1e-9).
  OpenImageIO    : opens it; width and height equal the clean DNG's.
A burst's frames (`_iso<ISO>_f<NN>.dng`) get the same checks; the noise-mean check compares
a moved frame (non-identity transform in the plan's burst) inside its valid rectangle with
the clean raw warped there by nothing else than the same motion: it is skipped for those
(tests/validators/burst_check.py checks their geometry).
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


def dngpy_probe(path):
    code = (
        "import dngpy, sys, json\n"
        "d = dngpy.Dng(sys.argv[1])\n"
        "print(json.dumps({'wb': list(d.get_white_balance())}))\n"
    )
    r = subprocess.run([sys.executable, "-c", code, path], capture_output=True, text=True)
    msgs = set(
        l.strip()
        for l in (r.stderr + r.stdout).splitlines()
        if l.strip().startswith("*** Error") or l.strip().startswith("*** Warning")
    )
    info = None
    if r.returncode == 0:
        try:
            info = json.loads(r.stdout.strip().splitlines()[-1])
        except Exception:  # noqa: BLE001
            info = None
    return r.returncode, msgs, info, r.stderr[-300:]


def rawpy_probe(path):
    import rawpy

    try:
        with rawpy.imread(path) as r:
            wb = np.array(r.camera_whitebalance[:3], dtype=float)
            s = r.sizes
            raw = r.raw_image.copy()
            vis = raw[s.top_margin:s.top_margin + s.raw_height, :]
            return {
                "raw": raw,
                "visible": r.raw_image_visible.copy(),
                "pattern": r.raw_pattern.tolist(),
                "white": int(r.white_level),
                "wb": wb / wb[1] if wb[1] else wb,
            }, None
    except Exception as e:  # noqa: BLE001
        return None, str(e)


def exif_iso_and_profile(path):
    import tifffile

    with tifffile.TiffFile(path) as tf:
        p = tf.pages[0]
        iso = None
        ex = p.tags.get(34665)
        if ex is not None and isinstance(ex.value, dict):
            iso = ex.value.get("ISOSpeedRatings")
            if isinstance(iso, (tuple, list)):
                iso = iso[0]
        prof = None
        for page in [p] + list(getattr(p, "pages", []) or []):
            t = page.tags.get(51041)
            if t is not None:
                prof = list(t.value)
        if prof is None and 330 in p.tags:
            for sub in p.pages if hasattr(p, "pages") else []:
                t = sub.tags.get(51041)
                if t is not None:
                    prof = list(t.value)
        return iso, prof


def moved(plan, frame):
    burst = plan.get("burst")
    if not burst or frame == 0:
        return False
    return burst["transforms"][frame]["affine"] != [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]


def oiio_size(path):
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        return oiio.geterror()
    spec = inp.spec()
    inp.close()
    return (spec.width, spec.height)


def plane_profile(params, bayer):
    out = []
    for colour in range(3):
        s = [params["positions"][i][0] for i in range(4) if bayer[i] == colour]
        o = [params["positions"][i][1] for i in range(4) if bayer[i] == colour]
        out += [sum(s) / len(s), sum(o) / len(o)]
    return out


def main():
    src, sidecar, outdir = sys.argv[1:4]
    sc = json.load(open(sidecar))
    plan = sc["plan"]
    neutral = np.array(plan["night_neutral"], dtype=float)
    bayer = plan["bayer"]
    src_rp, src_err = rawpy_probe(src)
    _, src_msgs, _, _ = dngpy_probe(src)
    dngs = [f for f in sc["outputs"]["files"] if f.endswith(".dng")]
    if not dngs:
        fail("sidecar lists no DNG outputs")
    clean = None
    for name in dngs:
        path = os.path.join(outdir, name)
        is_clean = name.endswith("_clean.dng")
        if is_clean:
            want_iso = plan["clean_iso"]
            want_prof = plane_profile(plan["clean_noise"], bayer)
        else:
            tail = name.rsplit("_iso", 1)[1][:-4]
            frame = 0
            if "_f" in tail:
                tail, f = tail.split("_f")
                frame = int(f)
            iso = int(tail)
            entry = [n for n in plan["noise"] if n["iso"] == iso]
            if not entry:
                fail(f"{name}: ISO {iso} not in the plan")
                continue
            want_iso = iso
            want_prof = plane_profile(entry[0]["params"], bayer)
        # rawpy
        rp, err = rawpy_probe(path)
        if rp is None:
            if src_rp is None:
                ok(f"{name}: rawpy refuses it, as it refuses the source ({src_err})")
            else:
                fail(f"{name}: rawpy cannot open it: {err}")
        else:
            if src_rp is not None:
                if rp["pattern"] != src_rp["pattern"]:
                    fail(f"{name}: raw_pattern {rp['pattern']} != source {src_rp['pattern']}")
                if rp["white"] != src_rp["white"]:
                    fail(f"{name}: white {rp['white']} != source {src_rp['white']}")
            want_wb = (1.0 / neutral) / (1.0 / neutral[1])
            rel = np.max(np.abs(rp["wb"] - want_wb) / want_wb)
            if rel > 1e-5:
                fail(f"{name}: rawpy camera_whitebalance {rp['wb']} != 1/neutral {want_wb}")
            else:
                ok(f"{name}: rawpy white balance = 1/night neutral (rel {rel:.1e})")
            if rp["visible"].max() > rp["white"]:
                fail(f"{name}: raw value {rp['visible'].max()} above white {rp['white']}")
            if is_clean:
                clean = rp["visible"].astype(np.float64)
            elif clean is not None and moved(plan, frame):
                ok(f"{name}: a moved frame (noise mean not compared with the clean raw)")
            elif clean is not None:
                # Away from white (saturated bulbs clip the noise there, biasing the mean).
                keep = clean < 0.8 * rp["white"]
                d = (rp["visible"].astype(np.float64) - clean)[keep]
                sd = d.std() if d.size else 0.0
                if sd == 0:
                    fail(f"{name}: identical to the clean raw (no noise)")
                elif abs(d.mean()) > 0.05 * sd:
                    fail(f"{name}: mean(noisy - clean) {d.mean():.3f} vs std {sd:.3f}")
                else:
                    ok(f"{name}: noise mean {d.mean():.3f}, std {sd:.2f} DN")
        # dngpy
        code, msgs, info, tail = dngpy_probe(path)
        if code != 0:
            fail(f"{name}: DNG SDK failed ({code}): {tail}")
        else:
            new = msgs - src_msgs
            if new:
                fail(f"{name}: DNG SDK messages not produced by the source: {sorted(new)}")
            else:
                ok(f"{name}: DNG SDK opens it, no new errors/warnings")
            if info is not None:
                wb = np.array(info["wb"], dtype=float)
                wb = wb / wb[1]
                if np.max(np.abs(wb - neutral) / neutral) > 1e-5:
                    fail(f"{name}: DNG SDK neutral {wb} != sidecar {neutral}")
        # OpenImageIO
        oi = oiio_size(path)
        if isinstance(oi, str):
            fail(f"{name}: OpenImageIO cannot open it: {oi}")
        elif oi != oiio_size(os.path.join(outdir, dngs[0])):
            fail(f"{name}: OpenImageIO size {oi} != the clean DNG's")
        else:
            ok(f"{name}: OpenImageIO opens it ({oi[0]}x{oi[1]})")
        # tags
        iso, prof = exif_iso_and_profile(path)
        if iso != want_iso:
            fail(f"{name}: Exif ISO {iso}, expected {want_iso}")
        else:
            ok(f"{name}: Exif ISO {iso}")
        if prof is None:
            fail(f"{name}: no NoiseProfile")
        else:
            rel = max(abs(a - b) / max(abs(b), 1e-300) for a, b in zip(prof, want_prof))
            if len(prof) != 6 or rel > 1e-9:
                fail(f"{name}: NoiseProfile {prof} != plan {want_prof}")
            else:
                ok(f"{name}: NoiseProfile matches the plan")
    if FAILS:
        print(f"{len(FAILS)} check(s) failed")
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
