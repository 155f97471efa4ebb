"""The authors' fixed k-fold lists (``utils/k_fold_indices_saved.p`` of the release) as a
day2night fold manifest (folds.py), for ``--folds-file``.

The release's file is a pickled dict with the keys ``train_index_all``, ``val_index_all`` and
``test_index_all``; each holds one list per fold (3 lists of 60, 10 and 35 indices, sorted).
The train and val entries are numpy int32 scalars, the test entries Python ints. Index ``j``
is the ``j``-th of the sorted ``night_real/clean/*.png``, i.e. the processed tree's scene
``"%03d" % j``; here it is the ``j``-th sorted scene id of the real set.

A pickle can run any code when it is loaded, and a restricted unpickler is not a boundary
(issue 42), so the pickle is never unpickled: foldpickle.py walks its opcodes as data and
accepts only the shape above. The file is read once, at most :data:`MAX_BYTES` of a regular
file (a FIFO or a device is refused before reading), and those bytes are hashed for the run's
``folds_sha256``. An index that appears twice in one list is refused.

The JSON export (``FORMAT``; ``python -m day2night.experiment.release_folds export IN.p -o
OUT.json`` writes it) is the same dict with plain integers::

    {"format": "day2night-release-folds/1",
     "train_index_all": [[...60 ints...], [...], [...]],
     "val_index_all":   [[...10 ints...], [...], [...]],
     "test_index_all":  [[...35 ints...], [...], [...]]}

``format`` may be left out; any other key is an error. A UTF-8 byte order mark is
skipped; nesting deeper than the lists, a key given twice and a number of more than
:data:`MAX_DIGITS` digits are refused before any list is built."""

import argparse
import collections
import hashlib
import json
import numbers
import os
import re
import stat
import sys

from . import folds as folds_mod
from . import foldpickle
from ..atomic import write_json

FORMAT = "day2night-release-folds/1"
KEYS = ("train_index_all", "val_index_all", "test_index_all")
PARTS = dict(zip(KEYS, ("train", "val", "test")))
MAX_BYTES = 1 << 20
#: The digits of a number in the JSON export (a scene index has a few).
MAX_DIGITS = 18
#: The JSON export's nesting: the dict, its lists of folds, each fold's list.
MAX_DEPTH = 3


def _error(path, why):
    return folds_mod.FoldError(f"--folds-file {path}: {why}")


def read_bytes(path):
    """The bytes of a fold file: a regular file of at most :data:`MAX_BYTES`, read once
    (opened without blocking, so a FIFO or a device is refused before any read)."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as e:
        raise _error(path, f"cannot read it ({e.strerror or e})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _error(path, "not a regular file (a FIFO, a device or a folder); give the "
                         "release's k_fold_indices_saved.p or its JSON export")
        if st.st_size > MAX_BYTES:
            raise _error(path, f"{st.st_size} bytes, larger than {MAX_BYTES}: not a "
                         "fold-index file")
        chunks, size = [], 0
        while size <= MAX_BYTES:
            chunk = os.read(fd, MAX_BYTES + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as e:
        raise _error(path, f"cannot read it ({e.strerror or e})") from None
    finally:
        os.close(fd)
    if size > MAX_BYTES:
        raise _error(path, f"larger than {MAX_BYTES} bytes: not a fold-index file")
    return b"".join(chunks)


class _JsonRefused(ValueError):
    pass


def _json_int(text):
    if len(text.lstrip("-")) > MAX_DIGITS:
        raise _JsonRefused(f"a number of {len(text.lstrip('-'))} digits (at most {MAX_DIGITS})")
    return int(text)


def _json_float(text):
    if len(text) > 2 * MAX_DIGITS:
        raise _JsonRefused(f"a number of {len(text)} characters")
    return float(text)


def _json_object(pairs):
    seen = set()
    for k, _ in pairs:
        if k in seen:
            raise _JsonRefused(f"the key {ascii(k)[:40]} appears twice")
        seen.add(k)
    return dict(pairs)


_SPECIAL = re.compile(r'["\\\[\]{}]')


def _json_depth(text):
    """The deepest nesting of ``text``'s arrays and objects (strings skipped), found in one
    pass over its quotes, backslashes and brackets, without a parser's recursion."""
    depth = deepest = 0
    in_string, escaped_at = False, -1
    for m in _SPECIAL.finditer(text):
        ch, i = m.group(), m.start()
        if i == escaped_at:
            continue
        if in_string:
            if ch == "\\":
                escaped_at = i + 1
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_DEPTH:
                break
        elif ch in "]}":
            depth -= 1
    return deepest


def _load_json(path, data):
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise _error(path, f"not valid JSON (not UTF-8: {e})") from None
    if _json_depth(text) > MAX_DEPTH:
        raise _error(path, f"JSON nested deeper than {MAX_DEPTH} levels (a dict of lists of "
                     "folds of indices)")
    try:
        return json.loads(text, parse_int=_json_int, parse_float=_json_float,
                          object_pairs_hook=_json_object)
    except _JsonRefused as e:
        raise _error(path, f"refused: {e}") from None
    except (ValueError, RecursionError) as e:
        raise _error(path, f"not valid JSON ({str(e)[:200]})") from None


def _load_pickle(path, data):
    try:
        return foldpickle.read(data)
    except foldpickle.PickleRefused as e:
        raise _error(path, f"refused: not the release's fold-index pickle ({e})") from None


def _index(v, where):
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or int(v) < 0:
        raise folds_mod.FoldError(f"{where}: {_show(v)} is not a scene index (a non-negative "
                                  "integer)")
    return int(v)


def _show(v):
    """A value for a message: short whatever it holds (never a repr of a large structure)."""
    if isinstance(v, (list, dict, tuple)):
        return f"a {type(v).__name__} of {len(v)} items"
    return ascii(v)[:40]


def _key(k):
    """A dict key for a message: as it is when short and printable, else escaped and cut."""
    return k if isinstance(k, str) and k.isprintable() and len(k) <= 40 else ascii(k)[:40]


def _fold(path, key, i, fold):
    """One fold's list of indices, checked: integers, each once (a linear check)."""
    if not isinstance(fold, list):
        raise _error(path, f"{key}[{i}] is not a list")
    out = [_index(v, f"--folds-file {path}: {key}[{i}]") for v in fold]
    if len(set(out)) != len(out):
        count = collections.Counter(out)
        j = next(j for j in out if count[j] > 1)
        raise _error(path, f"{key}[{i}] holds index {j} {count[j]} times: each scene is "
                     "listed once per fold")
    return out


def _check_lists(obj, path):
    """{key: [[int]]} from the loaded dict, with every shape checked."""
    if not isinstance(obj, dict):
        raise _error(path, f"{_show(obj)}, not a dict of {', '.join(KEYS)}")
    extra = sorted(_key(k) for k in obj if k not in KEYS and k != "format")
    missing = [k for k in KEYS if k not in obj]
    if missing or extra:
        raise _error(path, f"keys {', '.join(sorted(_key(k) for k in obj)[:8])}; expected "
                     f"{', '.join(KEYS)}"
                     + (f" (missing {', '.join(missing)})" if missing else "")
                     + (f" (unknown {', '.join(extra[:8])})" if extra else ""))
    if obj.get("format", FORMAT) != FORMAT:
        raise _error(path, f"format {_show(obj['format'])}, not {FORMAT}")
    out = {}
    for k in KEYS:
        lists = obj[k]
        if not isinstance(lists, list) or not lists:
            raise _error(path, f"{k} is not a list of folds")
        out[k] = [_fold(path, k, i, fold) for i, fold in enumerate(lists)]
    counts = {len(out[k]) for k in KEYS}
    if len(counts) != 1:
        raise _error(path, "the lists hold different numbers of folds "
                     f"({', '.join(f'{k}: {len(out[k])}' for k in KEYS)})")
    return out


def parse(path, data):
    """The release's lists ``{key: [[int, ...] per fold]}`` of a fold file's bytes ``data``
    (the pickle or the JSON export, told apart by content; a UTF-8 BOM is skipped)."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if data.lstrip()[:1] in (b"{", b"["):
        obj = _load_json(path, data)
    elif data[:1] == b"\x80":
        obj = _load_pickle(path, data)
    else:
        raise _error(path, "neither a pickle of protocol 2 to 5 (the release's "
                     "k_fold_indices_saved.p) nor the JSON export (a UTF-8 object)")
    return _check_lists(obj, path)


def read_release_file(path):
    """(lists, SHA-256 hex of the bytes they were read from) of a fold file (:func:`parse` of
    :func:`read_bytes`). Raises FoldError naming the file and the reason."""
    data = read_bytes(path)
    return parse(path, data), hashlib.sha256(data).hexdigest()


def read_release_folds(path):
    """The release's lists ``{key: [[int, ...] per fold]}`` from its pickle or the JSON export.
    Raises FoldError naming the file and the reason."""
    return read_release_file(path)[0]


def to_manifest(lists, scenes, source=None):
    """The fold manifest (folds.py's format) of the release's ``lists`` over the real set's
    ``scenes`` (ids): index ``j`` is the ``j``-th sorted id. Every index must name a scene and
    the lists must pass ``folds.check_folds`` (disjoint, covering, test folds partition)."""
    ids = sorted(str(s) for s in scenes)
    n = len(ids)
    top = max((j for k in KEYS for f in lists[k] for j in f), default=-1)
    if top >= n:
        raise folds_mod.FoldError(
            f"--folds-file {source}: index {top} names scene number {top + 1}, but the real set "
            f"has {n} scenes (the release's lists index its 105 processed night_real scenes "
            "000-104)"
        )
    splits = []
    for i in range(len(lists[KEYS[0]])):
        s = {"fold": i}
        for k in KEYS:
            s[PARTS[k]] = [ids[j] for j in lists[k][i]]
        splits.append(s)
    manifest = {"format": folds_mod.FORMAT, "seed": 0, "folds": len(splits), "scenes": ids,
                "splits": splits, "source": {"file": str(source), "lists": lists}}
    try:
        folds_mod.check_folds(manifest)
    except folds_mod.FoldError as e:
        raise folds_mod.FoldError(f"--folds-file {source}: {e}") from None
    return manifest


def make_run_folds(scenes, folds=3, seed=0, folds_file=None, folds_sha256=None):
    """A run's new fold manifest: seeded (``folds.make_folds``), or the lists of
    ``folds_file`` (the release's ``k_fold_indices_saved.p`` or its JSON export) mapped onto
    the sorted ``scenes``, recorded with the run's ``seed``. ``folds_sha256``: the hash the
    run recorded when it resolved its options; bytes that differ now are refused."""
    if folds_file is None:
        return folds_mod.make_folds(scenes, folds, seed=seed)
    lists, sha = read_release_file(folds_file)
    if folds_sha256 is not None and sha != folds_sha256:
        raise _error(folds_file, f"changed while the run started (SHA-256 {sha}, it was "
                     f"{folds_sha256}): rerun")
    manifest = to_manifest(lists, scenes, source=folds_file)
    manifest["seed"] = int(seed)
    manifest["source"]["sha256"] = sha
    return manifest


def export(src, dst):
    """Write the JSON export of a release fold file (pickle or JSON)."""
    lists = read_release_folds(src)
    write_json(dst, {"format": FORMAT, **lists})


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m day2night.experiment.release_folds",
        description="Export the release's k_fold_indices_saved.p as JSON (its opcodes read as "
        "data, never unpickled: docs/experiment.md).",
    )
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export", help="write the JSON export")
    e.add_argument("input")
    e.add_argument("-o", "--output", required=True)
    a = p.parse_args(argv)
    try:
        export(a.input, a.output)
    except folds_mod.FoldError as err:
        print(f"release_folds: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"release_folds: error: {a.output}: cannot write it ({err.strerror or err})",
              file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
