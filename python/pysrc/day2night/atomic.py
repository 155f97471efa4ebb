"""Files written whole or not at all: a temporary file in the same folder, flushed, synced,
then renamed over the final name (the Python side of the crate's ``output`` module). The
package's one atomic writer: the experiment, the trainer's checkpoints and history, the fixed
pairs and the PNG writer all go through it.

Files are created with mode 0666 less the process umask (0644 under umask 022), as ``open``
and the command line's outputs are, not owner-only as ``tempfile.mkstemp`` would make them:
a run folder shared with a group or served by a web server stays readable."""

import contextlib
import json
import os
import pathlib
import secrets

#: How many random temporary names are tried before giving up (each taken name is a
#: leftover of a killed writer or another writer's file; 8 random hex digits per try).
TEMP_TRIES = 100


def create_temp(folder, prefix, suffix=".tmp", mode=0o666):
    """(fd, path) of a new file ``folder/<prefix><8 hex digits><suffix>``, opened for writing
    with ``O_EXCL`` (never another writer's file) and ``mode`` less the umask, the mode
    ``open`` gives (``tempfile.mkstemp`` forces 0600)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(TEMP_TRIES):
        path = os.path.join(folder, f"{prefix}{secrets.token_hex(4)}{suffix}")
        try:
            return os.open(path, flags, mode), path
        except FileExistsError:
            continue
    raise FileExistsError(f"{folder}: no free temporary name {prefix}*{suffix} in "
                          f"{TEMP_TRIES} tries")


def create_temp_dir(folder, prefix, suffix=".tmp"):
    """A new folder ``folder/<prefix><8 hex digits><suffix>`` with mode 0777 less the umask
    (``tempfile.mkdtemp`` forces 0700), for a tree written then renamed into place."""
    for _ in range(TEMP_TRIES):
        path = pathlib.Path(folder) / f"{prefix}{secrets.token_hex(4)}{suffix}"
        try:
            path.mkdir(0o777)
            return path
        except FileExistsError:
            continue
    raise FileExistsError(f"{folder}: no free temporary name {prefix}*{suffix} in "
                          f"{TEMP_TRIES} tries")


@contextlib.contextmanager
def open_atomic(path):
    """A binary file to write ``path`` through: a temporary file in the same folder, flushed,
    synced and renamed over ``path`` when the block ends, removed if it raises (never
    half-written). For writers that take a file object (``torch.save``, ``np.save``)."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = create_temp(path.parent, f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def write_bytes(path, data: bytes):
    """Write ``data`` to ``path`` through a temporary file + rename (never half-written)."""
    with open_atomic(path) as f:
        f.write(data)


def write_text(path, text: str):
    write_bytes(path, text.encode("utf-8"))


def write_json(path, obj):
    """JSON with sorted keys and a final newline (byte-identical for equal objects)."""
    write_text(path, json.dumps(obj, indent=1, sort_keys=True, allow_nan=True) + "\n")
