"""Files written whole or not at all: a temporary file in the same folder, flushed, synced,
then renamed over the final name (the Python side of the crate's ``output`` module). The
package's one atomic writer: the experiment, the trainer's checkpoints and history, the fixed
pairs and the PNG writer all go through it."""

import contextlib
import json
import os
import pathlib
import tempfile


@contextlib.contextmanager
def open_atomic(path):
    """A binary file to write ``path`` through: a temporary file in the same folder, flushed,
    synced and renamed over ``path`` when the block ends, removed if it raises (never
    half-written). For writers that take a file object (``torch.save``, ``np.save``)."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
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
