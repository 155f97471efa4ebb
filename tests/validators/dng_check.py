#!/usr/bin/env python3
"""Independent checks of DNGs written by day2night against the DNG they were made from.

usage: dng_check.py SOURCE.dng OUT.dng [OUT2.dng ...] [--pixels FILE --width W --height H]

For every OUT:
  rawpy (LibRaw)   : raw_image, raw_pattern, black_level_per_channel, white_level and
                     camera_whitebalance (green-normalised) equal to the SOURCE's; with
                     --pixels, raw_image also equals those expected values (little-endian u16,
                     W x H, already linearized when the DNG has a LinearizationTable).
                     Skipped (printed) only when LibRaw refuses the SOURCE too (e.g. 7x9).
  dngpy (DNG SDK)  : opens OUT; no `*** Error` and no `*** Warning` line on stderr that the
                     SOURCE did not produce; stage-1 raw pixels and white balance equal SOURCE's.
  OpenImageIO      : opens OUT; width/height/bits equal IFD0's (the raw, or the thumbnail
                     when the raw is in a SubIFD) and, for raw in IFD0, the SOURCE's. Known
                     limitation: the PyPI build's libtiff cannot decode lossless JPEG, so
                     LJ92 in IFD0 is reported as KNOWN, not checked.
  iinfo            : Debian openimageio-tools (OpenImageIO through LibRaw) (required when
                     D2N_REQUIRE_TOOLS=1): same decoded width/height/channels as the SOURCE.
  tifffile         : parses OUT; DNG tags present in IFD0/raw IFD; entries sorted and unique;
                     every strip/tile offset even; stale tags absent; uncompressed 16-bit raw
                     data decodes to the expected pixels.
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
    """Open with the DNG SDK in a subprocess (its messages go to the C stderr)."""
    code = (
        "import dngpy, sys, json, numpy as np\n"
        "d = dngpy.Dng(sys.argv[1])\n"
        "px = np.asarray(d.raw_pixels)\n"
        "np.save(sys.argv[2], px)\n"
        "print(json.dumps({'wb': list(d.get_white_balance()), 'pattern': d.get_bayer_pattern()}))\n"
    )
    import tempfile, os

    with tempfile.TemporaryDirectory() as td:
        npy = os.path.join(td, "px.npy")
        r = subprocess.run(
            [sys.executable, "-c", code, path, npy], capture_output=True, text=True
        )
        msgs = set(
            l.strip()
            for l in (r.stderr + r.stdout).splitlines()
            if l.strip().startswith("*** Error") or l.strip().startswith("*** Warning")
        )
        info = None
        px = None
        if r.returncode == 0:
            try:
                info = json.loads(r.stdout.strip().splitlines()[-1])
                px = np.load(npy)
            except Exception as e:  # noqa: BLE001
                info = None
                msgs.add(f"probe output unreadable: {e}")
        return r.returncode, msgs, info, px, r.stderr[-400:]


def rawpy_probe(path):
    import rawpy

    try:
        with rawpy.imread(path) as r:
            wb = np.array(r.camera_whitebalance[:3], dtype=float)
            if wb[1] != 0:
                wb = wb / wb[1]
            return {
                "raw": r.raw_image.copy(),
                "pattern": r.raw_pattern.tolist(),
                "black": list(r.black_level_per_channel),
                "white": int(r.white_level),
                "wb": wb,
            }, None
    except Exception as e:  # noqa: BLE001
        return None, str(e)


def oiio_probe(path):
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        return None, oiio.geterror()
    spec = inp.spec()
    res = (spec.width, spec.height, spec.nchannels, str(spec.format),
           spec.get_int_attribute("oiio:BitsPerSample", 0))
    inp.close()
    return res, None


def iinfo_probe(path):
    """Debian's OpenImageIO (openimageio-tools) reads raw files through LibRaw."""
    import os
    import re
    exe = os.environ.get("D2N_IINFO", "/usr/bin/iinfo")
    if not os.path.exists(exe):
        return None, "not installed"
    r = subprocess.run([exe, path], capture_output=True, text=True)
    m = re.search(r":\s*(\d+)\s*x\s*(\d+),\s*(\d+) channel", r.stdout)
    if r.returncode != 0 or not m:
        return None, (r.stdout + r.stderr).strip()[-200:]
    return tuple(int(g) for g in m.groups()), None


STALE = {50972: "RawImageDigest", 51111: "NewRawImageDigest", 50828: "OriginalRawFileData",
         50973: "OriginalRawFileDigest", 37500: "MakerNote", 50740: "DNGPrivateData"}
IFD0_REQUIRED = {50706: "DNGVersion", 50707: "DNGBackwardVersion", 50708: "UniqueCameraModel",
                 50721: "ColorMatrix1", 274: "Orientation", 271: "Make", 272: "Model",
                 305: "Software", 50781: "RawDataUniqueID", 34665: "ExifIFD"}
RAW_REQUIRED = {33421: "CFARepeatPatternDim", 33422: "CFAPattern", 50710: "CFAPlaneColor",
                50711: "CFALayout", 50714: "BlackLevel", 50717: "WhiteLevel"}


def tifffile_check(path, expected):
    import tifffile

    with tifffile.TiffFile(path) as tf:
        pages = list(tf.pages)
        ifd0 = pages[0]
        # SubIFDs as tifffile exposes them.
        subs = []
        if 330 in ifd0.tags:
            v = ifd0.tags[330].value
            for off in v if isinstance(v, (list, tuple)) else [v]:
                tf.filehandle.seek(off)
                subs.append(tifffile.TiffPage(tf, index=0))
        ifds = [ifd0] + subs
        raw = [p for p in ifds if p.tags.get(254) is not None and p.tags[254].value == 0]
        if len(raw) != 1:
            fail(f"{path}: {len(raw)} IFDs with NewSubFileType 0 (want 1)")
            return
        raw = raw[0]
        for code, name in IFD0_REQUIRED.items():
            if code not in ifd0.tags:
                fail(f"{path}: IFD0 lacks {name}")
        for code, name in RAW_REQUIRED.items():
            if code not in raw.tags:
                fail(f"{path}: raw IFD lacks {name}")
        exif = ifd0.tags[34665].value if 34665 in ifd0.tags else {}
        for p in ifds:
            codes = [t.code for t in p.tags.values()]
            if codes != sorted(set(codes)):
                fail(f"{path}: IFD entries not sorted/unique: {codes}")
            for t in p.tags.values():
                if t.code in STALE:
                    fail(f"{path}: stale tag {STALE[t.code]} written")
                if t.valueoffset % 2 and t.valuebytecount > 4:
                    fail(f"{path}: tag {t.code} value at odd offset {t.valueoffset}")
            offs = list(p.dataoffsets or [])
            if any(o % 2 for o in offs):
                fail(f"{path}: strip/tile at odd offset")
        if isinstance(exif, dict) and "MakerNote" in exif:
            fail(f"{path}: MakerNote carried")
        if (raw.compression == 1 and raw.bitspersample == 16 and expected is not None
                and 50712 not in raw.tags):
            arr = raw.asarray()
            if arr.shape != expected.shape or not np.array_equal(arr, expected):
                fail(f"{path}: tifffile-decoded raw differs from expected pixels")
            else:
                ok(f"{path}: tifffile decodes identical raw pixels")
        ok(f"{path}: tifffile parsed; compression {raw.compression}, bps {raw.bitspersample}, "
           f"{'tiles' if raw.is_tiled else 'strips'}, raw in {'IFD0' if raw is ifd0 else 'SubIFD'}")
        return (ifd0.imagewidth, ifd0.imagelength, ifd0.bitspersample, int(ifd0.compression),
                raw is ifd0)


def main():
    args = sys.argv[1:]
    pix = None
    if "--pixels" in args:
        i = args.index("--pixels")
        pix_path = args[i + 1]
        w = int(args[args.index("--width") + 1])
        h = int(args[args.index("--height") + 1])
        for flag in ("--pixels", "--width", "--height"):
            j = args.index(flag)
            del args[j:j + 2]
        pix = np.fromfile(pix_path, dtype="<u2").reshape(h, w)
    src, outs = args[0], args[1:]

    s_rp, s_rp_err = rawpy_probe(src)
    s_code, s_msgs, s_info, s_px, _ = dngpy_probe(src)
    s_oiio, _ = oiio_probe(src)
    s_iinfo, s_iinfo_err = iinfo_probe(src)
    if s_iinfo_err == "not installed":
        if os.environ.get("D2N_REQUIRE_TOOLS") == "1":
            fail("iinfo (Debian openimageio-tools) not installed but D2N_REQUIRE_TOOLS=1 "
                 "(scripts/test.sh sets it; .ci/run installs iinfo)")
        print("SKIP Debian OpenImageIO (iinfo, LibRaw) checks: /usr/bin/iinfo not installed "
              "(Debian openimageio-tools)")

    for out in outs:
        # rawpy / LibRaw
        o_rp, o_err = rawpy_probe(out)
        if s_rp is None:
            print(f"SKIP rawpy on {out}: LibRaw refuses the source too ({s_rp_err})")
        elif o_rp is None:
            fail(f"{out}: rawpy cannot open it: {o_err}")
        else:
            if o_rp["raw"].shape != s_rp["raw"].shape or not np.array_equal(o_rp["raw"], s_rp["raw"]):
                fail(f"{out}: rawpy raw_image differs from source")
            elif pix is not None and not np.array_equal(o_rp["raw"], pix):
                fail(f"{out}: rawpy raw_image differs from day2night's pixels")
            else:
                ok(f"{out}: rawpy raw_image identical {o_rp['raw'].shape}")
            for k in ("pattern", "black", "white"):
                if o_rp[k] != s_rp[k]:
                    fail(f"{out}: rawpy {k} {o_rp[k]} != source {s_rp[k]}")
            if not np.allclose(o_rp["wb"], s_rp["wb"], rtol=1e-4):
                fail(f"{out}: rawpy camera_whitebalance {o_rp['wb']} != source {s_rp['wb']}")
            else:
                ok(f"{out}: rawpy pattern/black/white/wb identical")
        # DNG SDK
        o_code, o_msgs, o_info, o_px, o_tail = dngpy_probe(out)
        if o_code != 0 or o_info is None:
            fail(f"{out}: DNG SDK failed to read it (rc {o_code}): {o_tail}")
        else:
            new = o_msgs - s_msgs
            if new:
                fail(f"{out}: DNG SDK messages the source did not have: {sorted(new)}")
            else:
                ok(f"{out}: DNG SDK: no new errors/warnings ({len(o_msgs)} shared with source)")
            if s_px is not None and (o_px.shape != s_px.shape or not np.array_equal(o_px, s_px)):
                fail(f"{out}: DNG SDK stage-1 pixels differ from the source's")
            if s_info is not None:
                if not np.allclose(o_info["wb"], s_info["wb"], rtol=1e-6):
                    fail(f"{out}: DNG SDK white balance {o_info['wb']} != {s_info['wb']}")
                if o_info["pattern"] != s_info["pattern"]:
                    fail(f"{out}: DNG SDK pattern {o_info['pattern']} != {s_info['pattern']}")
        # Debian OpenImageIO through LibRaw: same decoded size as the source.
        if s_iinfo_err != "not installed":
            o_iinfo, o_iinfo_err = iinfo_probe(out)
            if s_iinfo is None or s_rp is None:
                print(f"SKIP iinfo on {out}: LibRaw refuses the source "
                      f"({s_iinfo_err or s_rp_err}); iinfo would fall back to libtiff")
            elif o_iinfo != s_iinfo:
                fail(f"{out}: Debian OpenImageIO/LibRaw sees {o_iinfo} ({o_iinfo_err}), "
                     f"source {s_iinfo}")
            else:
                ok(f"{out}: Debian OpenImageIO/LibRaw decodes {o_iinfo[0]}x{o_iinfo[1]}")
        # tifffile
        t_ifd0 = None
        try:
            t_ifd0 = tifffile_check(out, pix)
        except Exception as e:  # noqa: BLE001
            fail(f"{out}: tifffile failed: {e!r}")
        # OpenImageIO (PyPI build: libtiff, no LibRaw): it sees IFD0 (the raw, or the
        # thumbnail when the raw is in a SubIFD); libtiff has no lossless-JPEG codec.
        o_oiio, err = oiio_probe(out)
        if t_ifd0 is not None and t_ifd0[3] == 7 and t_ifd0[4]:
            if o_oiio is None:
                print(f"KNOWN {out}: OpenImageIO/libtiff cannot decode lossless JPEG in IFD0 "
                      f"(the SubIFD variant is checked instead)")
            else:
                ok(f"{out}: OpenImageIO opens it: {o_oiio}")
        elif o_oiio is None:
            fail(f"{out}: OpenImageIO cannot open it: {err}")
        elif t_ifd0 is not None and (o_oiio[0], o_oiio[1], o_oiio[4]) != t_ifd0[:3]:
            fail(f"{out}: OpenImageIO sees {o_oiio}, IFD0 is {t_ifd0[:3]}")
        elif (t_ifd0 is not None and t_ifd0[4] and s_oiio is not None and s_oiio[2] == 1
              and (o_oiio[0], o_oiio[1], o_oiio[4]) != (s_oiio[0], s_oiio[1], s_oiio[4])):
            fail(f"{out}: OpenImageIO size/bits {o_oiio} != source {s_oiio}")
        else:
            ok(f"{out}: OpenImageIO opens it: {o_oiio}")

    if FAILS:
        print(f"{len(FAILS)} check(s) failed")
        sys.exit(1)


if __name__ == "__main__":
    main()
