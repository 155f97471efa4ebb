"""The run folder's lock (RUN/driver.lock): one driver at a time on a run folder.

The lock file holds its holder's host and pid (JSON). It is made whole or not at all: the
record is written to a temporary file, then hard-linked to the lock's name, which fails when
the name exists. A second driver is refused with a one-line error naming the holder; a lock
whose holder is dead (a pid that no longer exists on this host: a killed driver) is taken
over with a warning. A lock held from another host is never taken over: only its user knows
whether that driver is gone (the message says which file to delete)."""

import json
import os
import pathlib
import socket
import tempfile

from .config import ExperimentError
from .prepare import log

NAME = "driver.lock"


class RunFolderBusy(ExperimentError):
    """Another driver holds the run folder (exit 2)."""


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def _holder(path):
    try:
        rec = json.loads(path.read_text(encoding="utf-8"))
        return str(rec["host"]), int(rec["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def acquire(out):
    """Take RUN/driver.lock for this process (the run folder is made if absent); returns
    the lock's path, for :func:`release`."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path, me = out / NAME, (socket.gethostname(), os.getpid())
    fd, tmp = tempfile.mkstemp(prefix=f".{NAME}.", suffix=".tmp", dir=out)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump({"host": me[0], "pid": me[1]}, f)
            f.flush()
            os.fsync(f.fileno())
        try:
            os.link(tmp, path)
            return path
        except FileExistsError:
            pass
        held = _holder(path)
        if held is None:
            raise RunFolderBusy(f"{path}: the run folder's lock is unreadable; if no other "
                                "driver runs on this folder, delete it and rerun")
        host, pid = held
        if host != me[0] or _alive(pid):
            raise RunFolderBusy(
                f"{out} is in use by another driver (host {host}, pid {pid}): wait for it, "
                f"or if that driver is gone, delete {path} and rerun")
        log(f"warning: taking over the stale lock {path} of host {host}, pid {pid} (no "
            "such process: a driver that was killed)")
        os.replace(tmp, path)
        return path
    finally:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass


def release(path):
    """Remove the lock ``path`` (None: none taken) when this process still holds it."""
    if path is not None and _holder(path) == (socket.gethostname(), os.getpid()):
        os.unlink(path)
