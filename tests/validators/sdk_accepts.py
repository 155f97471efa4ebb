#!/usr/bin/env python3
"""Does the Adobe DNG SDK (dngpy) accept each file?

usage: sdk_accepts.py FILE.dng [FILE.dng ...]

Prints one JSON line per file: {"file": ..., "ok": bool, "messages": [...]}, where ok means
the SDK read the raw pixels and the white balance with no `*** Error` and no `*** Warning`
line, and messages are those lines (plus the exception text when reading failed). Each file
is opened in its own subprocess: the SDK writes its messages to the C-level stderr.
"""
import json
import subprocess
import sys

CODE = (
    "import dngpy, sys, numpy as np\n"
    "d = dngpy.Dng(sys.argv[1])\n"
    "np.asarray(d.raw_pixels)\n"
    "d.get_white_balance()\n"
)


def probe(path):
    r = subprocess.run([sys.executable, "-c", CODE, path], capture_output=True, text=True)
    text = r.stdout + r.stderr
    msgs = [l.strip() for l in text.splitlines() if l.strip().startswith("*** ")]
    if r.returncode != 0:
        last = [l for l in r.stderr.strip().splitlines() if l.strip()]
        msgs.append("exit %d: %s" % (r.returncode, last[-1] if last else ""))
    return {"file": path, "ok": r.returncode == 0 and not msgs, "messages": msgs}


if __name__ == "__main__":
    for p in sys.argv[1:]:
        print(json.dumps(probe(p)), flush=True)
