"""Put a program into a built wheel as one of its scripts (docs/release.md, "The wheel").

    python scripts/wheel_add_script.py WHEEL PROGRAM [NAME]

adds PROGRAM as ``<name>-<version>.data/scripts/<NAME>`` (NAME defaults to PROGRAM's
file name; mode 755) and rewrites the
wheel's RECORD with its sha256 and size, in place. pip installs the wheel's scripts into
the environment's ``bin/`` (``Scripts\\`` on Windows), so the program is a command on PATH.
maturin's own data folder (``[tool.maturin] data``) must exist whenever the project is
built, an sdist and ``pip install ./python`` included; adding the binary after the build
keeps those Python-only.
"""

import base64
import hashlib
import os
import shutil
import sys
import tempfile
import zipfile


def record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def add_script(wheel, program, name=None):
    with open(program, "rb") as f:
        payload = f.read()
    with zipfile.ZipFile(wheel) as zin:
        names = zin.namelist()
        dist_info = next(n.split("/")[0] for n in names if n.endswith(".dist-info/RECORD"))
        stem = dist_info[: -len(".dist-info")]
        target = f"{stem}.data/scripts/{name or os.path.basename(program)}"
        record = f"{dist_info}/RECORD"
        fd, tmp = tempfile.mkstemp(suffix=".whl", dir=os.path.dirname(os.path.abspath(wheel)))
        os.close(fd)
        try:
            with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
                lines = []
                for info in zin.infolist():
                    if info.filename in (target, record):
                        continue
                    zout.writestr(info, zin.read(info.filename))
                rec = zin.read(record).decode().splitlines()
                lines = [ln for ln in rec if ln and not ln.startswith(f"{target},")
                         and not ln.startswith(f"{record},")]
                info = zipfile.ZipInfo(target, date_time=(1980, 1, 1, 0, 0, 0))
                info.external_attr = (0o100755 << 16)
                info.compress_type = zipfile.ZIP_DEFLATED
                zout.writestr(info, payload)
                lines.append(record_line(target, payload))
                lines.append(f"{record},,")
                rinfo = zipfile.ZipInfo(record, date_time=(1980, 1, 1, 0, 0, 0))
                rinfo.external_attr = (0o100644 << 16)
                rinfo.compress_type = zipfile.ZIP_DEFLATED
                zout.writestr(rinfo, "\n".join(lines) + "\n")
            os.chmod(tmp, 0o644)
            shutil.move(tmp, wheel)
        except BaseException:
            os.unlink(tmp)
            raise
    return target


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: python scripts/wheel_add_script.py WHEEL PROGRAM [NAME]")
    print(add_script(*sys.argv[1:]))
