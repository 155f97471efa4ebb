"""The authors' fixed k-fold lists (``utils/k_fold_indices_saved.p`` of the release) as a
day2night fold manifest (folds.py), for ``--folds-file``.

The release's file is a pickled dict with the keys ``train_index_all``, ``val_index_all`` and
``test_index_all``; each holds one list per fold (3 lists of 60, 10 and 35 indices, sorted).
The train and val entries are numpy int32 scalars, the test entries Python ints. Index ``j``
is the ``j``-th of the sorted ``night_real/clean/*.png``, i.e. the processed tree's scene
``"%03d" % j``; here it is the ``j``-th sorted scene id of the real set.

A pickle can run any code when it is loaded, so it is read by an unpickler that resolves only
numpy's scalar constructor and ``numpy.dtype`` (the only globals the release's file holds)
and refuses every other global with an error naming it.

The JSON export (``FORMAT``; ``python -m day2night.experiment.release_folds export IN.p -o
OUT.json`` writes it) is the same dict with plain integers::

    {"format": "day2night-release-folds/1",
     "train_index_all": [[...60 ints...], [...], [...]],
     "val_index_all":   [[...10 ints...], [...], [...]],
     "test_index_all":  [[...35 ints...], [...], [...]]}

``format`` may be left out; any other key is an error."""

import argparse
import importlib
import io
import json
import numbers
import pathlib
import pickle
import sys

from . import folds as folds_mod
from ..atomic import write_json

FORMAT = "day2night-release-folds/1"
KEYS = ("train_index_all", "val_index_all", "test_index_all")
PARTS = dict(zip(KEYS, ("train", "val", "test")))
# module, name -> the module that holds it today (numpy 2 renamed numpy.core to numpy._core)
ALLOWED = {
    ("numpy.core.multiarray", "scalar"): ("numpy._core.multiarray", "numpy.core.multiarray"),
    ("numpy._core.multiarray", "scalar"): ("numpy._core.multiarray", "numpy.core.multiarray"),
    ("numpy", "dtype"): ("numpy",),
}
MAX_BYTES = 1 << 20


class RefusedGlobal(pickle.UnpicklingError):
    """A global the fold-index unpickler does not resolve."""


class _NumpyScalarsOnly(pickle.Unpickler):
    def find_class(self, module, name):
        where = ALLOWED.get((module, name))
        if where is None:
            raise RefusedGlobal(
                f"the pickle asks for the global {module}.{name}; only numpy's scalar "
                "constructor and numpy.dtype are allowed in a fold-index file"
            )
        for mod in where:
            try:
                return getattr(importlib.import_module(mod), name)
            except (ImportError, AttributeError):
                continue
        raise RefusedGlobal(f"numpy has no {module}.{name}")


def _load_pickle(path, data):
    try:
        return _NumpyScalarsOnly(io.BytesIO(data)).load()
    except RefusedGlobal as e:
        raise folds_mod.FoldError(f"--folds-file {path}: refused: {e}") from None
    except Exception as e:  # a damaged pickle fails in many ways; name the file either way
        raise folds_mod.FoldError(
            f"--folds-file {path}: not a readable fold-index pickle ({type(e).__name__}: {e})"
        ) from None


def _index(v, where):
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or int(v) < 0:
        raise folds_mod.FoldError(f"{where}: {v!r} is not a scene index (a non-negative integer)")
    return int(v)


def _check_lists(obj, path):
    """{key: [[int]]} from the loaded dict, with every shape checked."""
    if not isinstance(obj, dict):
        raise folds_mod.FoldError(f"--folds-file {path}: a {type(obj).__name__}, not a dict of "
                                  f"{', '.join(KEYS)}")
    extra = sorted(str(k) for k in obj if k not in KEYS and k != "format")
    missing = [k for k in KEYS if k not in obj]
    if missing or extra:
        raise folds_mod.FoldError(
            f"--folds-file {path}: keys {sorted(map(str, obj))}; expected {', '.join(KEYS)}"
            + (f" (missing {', '.join(missing)})" if missing else "")
            + (f" (unknown {', '.join(extra)})" if extra else "")
        )
    if obj.get("format", FORMAT) != FORMAT:
        raise folds_mod.FoldError(f"--folds-file {path}: format {obj['format']!r}, not {FORMAT}")
    out = {}
    for k in KEYS:
        lists = obj[k]
        if not isinstance(lists, (list, tuple)) or not lists:
            raise folds_mod.FoldError(f"--folds-file {path}: {k} is not a list of folds")
        out[k] = []
        for i, fold in enumerate(lists):
            if not isinstance(fold, (list, tuple)):
                raise folds_mod.FoldError(f"--folds-file {path}: {k}[{i}] is not a list")
            out[k].append([_index(v, f"--folds-file {path}: {k}[{i}]") for v in fold])
    counts = {len(out[k]) for k in KEYS}
    if len(counts) != 1:
        raise folds_mod.FoldError(
            f"--folds-file {path}: the lists hold different numbers of folds "
            f"({', '.join(f'{k}: {len(out[k])}' for k in KEYS)})"
        )
    return out


def read_release_folds(path):
    """The release's lists ``{key: [[int, ...] per fold]}`` from its pickle or the JSON export
    (told apart by content). Raises FoldError naming the file and the reason."""
    path = pathlib.Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_BYTES + 1)
    except OSError as e:
        raise folds_mod.FoldError(f"--folds-file {path}: cannot read it ({e.strerror or e})") \
            from None
    if len(data) > MAX_BYTES:
        raise folds_mod.FoldError(f"--folds-file {path}: larger than {MAX_BYTES} bytes; "
                                  "not a fold-index file")
    if data.lstrip()[:1] == b"{":
        try:
            obj = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise folds_mod.FoldError(f"--folds-file {path}: not valid JSON ({e})") from None
    else:
        obj = _load_pickle(path, data)
    return _check_lists(obj, path)


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


def export(src, dst):
    """Write the JSON export of a release fold file (pickle or JSON)."""
    lists = read_release_folds(src)
    write_json(dst, {"format": FORMAT, **lists})


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m day2night.experiment.release_folds",
        description="Export the release's k_fold_indices_saved.p as JSON (read without "
        "running pickle code: only numpy scalars are allowed).",
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
