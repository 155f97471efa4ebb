"""Inflate streams written by day2night::deflate with the reference C zlib (Python's zlib).

Usage: deflate_zlib.py DIR
DIR holds pairs NAME.raw (the input) and NAME.z (its zlib stream). For each pair the stream
must inflate with zlib (which checks the header and the Adler-32), end exactly at the end of
the file (no trailing bytes) and equal the input. Also re-checks the Adler-32 with
zlib.adler32 and the header (CM 8, CINFO <= 7, FCHECK, no dictionary). Exit 1 on any failure.
"""
import os
import sys
import zlib


def main() -> int:
    d = sys.argv[1]
    names = sorted(f[:-2] for f in os.listdir(d) if f.endswith(".z"))
    if not names:
        print("no streams found", file=sys.stderr)
        return 1
    bad = 0
    for name in names:
        raw = open(os.path.join(d, name + ".raw"), "rb").read()
        z = open(os.path.join(d, name + ".z"), "rb").read()
        try:
            cmf, flg = z[0], z[1]
            assert cmf & 15 == 8 and cmf >> 4 <= 7, "bad CMF"
            assert (cmf * 256 + flg) % 31 == 0, "bad FCHECK"
            assert not flg & 0x20, "dictionary flag set"
            o = zlib.decompressobj()
            out = o.decompress(z)
            out += o.flush()
            assert o.eof, "stream not terminated"
            assert o.unused_data == b"", f"{len(o.unused_data)} trailing bytes"
            assert out == raw, f"content differs ({len(out)} vs {len(raw)} bytes)"
            assert int.from_bytes(z[-4:], "big") == zlib.adler32(raw), "adler32"
        except Exception as e:  # noqa: BLE001 - report every failure
            print(f"{name}: FAIL: {e}", file=sys.stderr)
            bad += 1
            continue
        print(f"{name}: ok {len(raw)} -> {len(z)}")
    print(f"{len(names) - bad}/{len(names)} streams inflate with zlib {zlib.ZLIB_RUNTIME_VERSION}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
