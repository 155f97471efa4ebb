"""Checks of what an earlier run left in the run folder (docs/experiment.md, "A damaged run
folder"). Every file of RUN that a rerun reads is checked before anything is written or
trained: a file that cannot be used is a :class:`RunFolderError` naming it and saying what to
do (delete the file or the unit folder, or rerun with ``--restart-unit TASK/ROW/FOLD``).

- ``config.json``, ``folds.json``, ``units/.../scores.json``: a JSON object of the expected
  shape (a list, a number or garbage is refused); a unit's scores each within its metric's
  range, its history and initial validation drawable (scorecheck.py);
- ``data/**/*.npy``: a complete ``.npy`` file (the header's shape and dtype times the item
  size is the file's size), input stores (``.in.npy``, ``day2night.train.cache``: header,
  version and size) or float32 H x W x 3 inputs of the first format beside uint8 H x W x 3
  targets of the same size;
- ``units/.../model/last.pt`` and ``best.pt`` of a unit not done yet: a checkpoint torch reads
  whole (``day2night.train.trainer.load_checkpoint``). There is no earlier checkpoint to fall
  back to (``last.pt`` is replaced after every epoch), so a damaged one is an error."""

import json
import os
import pathlib

import numpy as np

from . import folds as folds_mod
from . import scorecheck
from .pairs import check_cached
from ..train.trainer import RESUME_STATE, CheckpointError, load_checkpoint

SCORE_KEYS = ("psnr", "ssim", "delta_e")


class RunFolderError(ValueError):
    """A damaged file of the run folder (the message names it and says what to do)."""


def unit_id(task, row_id, fold, seed=None):
    """The name ``--restart-unit`` takes: ``TASK/ROW/FOLD`` (``clean/ours/all``), or
    ``seed-S/TASK/ROW/FOLD`` for a unit of an extra seed S of ``--seeds`` (``seed``)."""
    uid = f"{task}/{row_id}/{fold}"
    return uid if seed is None else f"seed-{seed}/{uid}"


def unit_dir(out, uid):
    """The folder of the unit ``uid`` (:func:`unit_id`): RUN/units/TASK/ROW/FOLD, or
    RUN/seeds/S/units/TASK/ROW/FOLD for an extra seed S."""
    head, _, rest = uid.partition("/")
    if head.startswith("seed-"):
        return pathlib.Path(out) / "seeds" / head[len("seed-"):] / "units" / rest
    return pathlib.Path(out) / "units" / uid


def unit_advice(out, uid):
    folder = unit_dir(out, uid)
    return (f"delete the unit folder {folder} to train the unit again, or rerun with "
            f"--restart-unit {uid}")


def _kind(obj):
    return {list: "a JSON list", str: "a JSON string", bool: "a JSON boolean",
            type(None): "JSON null"}.get(type(obj), "a JSON number")


def read_object(path, what, advice):
    """The JSON object (dict) stored in ``path``; anything else is a RunFolderError."""
    path = pathlib.Path(path)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise RunFolderError(f"{path}: cannot read the {what} ({e.strerror or e}); {advice}") \
            from None
    except ValueError as e:  # JSONDecodeError, UnicodeDecodeError
        raise RunFolderError(f"{path}: damaged {what}: not JSON ({e}); {advice}") from None
    if not isinstance(obj, dict):
        raise RunFolderError(
            f"{path}: damaged {what}: {_kind(obj)} where a JSON object is expected; {advice}")
    return obj


CONFIG_ADVICE = ("delete it and rerun with the run's options: it is written again from them "
                 "(a finished run's table.json records them under \"config\")")
FOLDS_ADVICE = ("delete it and rerun: it is made again from --seed and the real set (the same "
                "folds while both are unchanged)")


def read_config(path):
    return read_object(path, "run configuration", CONFIG_ADVICE)


def read_folds(path, folds, seed):
    """The fold manifest of an earlier run, checked (folds.check_folds and the fold numbers
    the runner indexes with)."""
    m = read_object(path, "fold manifest", FOLDS_ADVICE)
    try:
        folds_mod.check_folds(m)
        splits = m["splits"]
        ok = [s["fold"] for s in splits] == list(range(len(splits)))
        lists = [s[k] for s in splits for k in ("train", "val", "test")] + [m["scenes"]]
        ok = ok and all(isinstance(x, list) and all(isinstance(i, str) for i in x)
                        for x in lists)
        if not ok:
            raise folds_mod.FoldError("fold numbers or scene lists of the wrong type")
        if m.get("folds") != folds or m.get("seed") != seed or len(splits) != folds:
            raise folds_mod.FoldError(
                f"made with {m.get('folds')!r} folds and seed {m.get('seed')!r}, this run "
                f"has {folds} and {seed}")
    except (folds_mod.FoldError, KeyError, TypeError, AttributeError) as e:
        raise RunFolderError(f"{path}: damaged fold manifest ({e}); {FOLDS_ADVICE}") from None
    return m


def _scores_problem(s, task, row_id, fold, keys, epochs=None):
    """What is wrong with a unit's scores (a string), or None (scorecheck.py: each score in
    its metric's range, the history and initial drawable)."""
    for k, want in (("task", task), ("row", row_id), ("fold", fold)):
        if s.get(k) != want:
            return f"its {k} is {s.get(k)!r}, not {want!r}"
    images, tests = s.get("images"), s.get("test_scenes")
    if not isinstance(images, list) or not isinstance(tests, list) \
            or not all(isinstance(t, str) for t in tests):
        return "no list of images or of test scenes"
    why = scorecheck.history_problem(s.get("history"), epochs) or \
        scorecheck.initial_problem(s.get("initial"))
    if why:
        return why
    seen = set()
    for i in images:
        if not isinstance(i, dict):
            return f"an image record that is not scores: {str(i)[:80]}"
        if any(m not in i for m in SCORE_KEYS) or i.get("input") not in keys \
                or not isinstance(i.get("scene"), str):
            return f"an image record without scores or input: {str(i)[:80]}"
        why = next(filter(None, (scorecheck.score_problem(m, i[m]) for m in SCORE_KEYS)), None)
        if why:
            return f"an image record of scene {i['scene'][:60]!r}: {why}"
        seen.add((i.get("scene"), i["input"]))
    want = {(t, k) for t in tests for k in keys}
    if seen != want:
        return f"its images are not every test scene x input ({len(seen)} of {len(want)})"
    return None


def read_scores(out, path, task, row_id, fold, keys, tests=None, seed=None, epochs=None):
    """A done unit's scores.json, checked against its task, row, fold, inputs ``keys``,
    (when given) its test scenes ``tests`` and the run's ``epochs``; ``seed``: an extra
    seed's unit (unit_id)."""
    advice = unit_advice(out, unit_id(task, row_id, fold, seed))
    s = read_object(path, "unit scores", advice)
    why = _scores_problem(s, task, row_id, fold, [str(k) for k in keys], epochs)
    if not why and tests is not None and sorted(s["test_scenes"]) != sorted(tests):
        why = "it was tested on other scenes than this run's fold (another real set?)"
    if why:
        raise RunFolderError(f"{path}: damaged unit scores: {why}; {advice}")
    return s


DATA_ADVICE = "delete it and rerun: a cached pair is made again from the inputs"


def npy_header(path):
    """(shape, dtype) of a complete ``.npy`` file, else RunFolderError naming it."""
    try:
        size = os.path.getsize(path)
        with open(path, "rb") as f:
            version = np.lib.format.read_magic(f)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(f)
            else:
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(f)
            start = f.tell()
    except (OSError, ValueError, EOFError, SyntaxError) as e:
        raise RunFolderError(
            f"{path}: damaged cached array ({size_text(path)}; {e}); {DATA_ADVICE}") from None
    want = start + int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if size != want:
        raise RunFolderError(
            f"{path}: damaged cached array: {size} bytes, its header needs {want} "
            f"(truncated); {DATA_ADVICE}")
    return tuple(shape), dtype


def size_text(path):
    try:
        return f"{os.path.getsize(path)} bytes"
    except OSError:
        return "unreadable"


def check_pair(xp, yp):
    """A cached (input, target) pair: float32 and uint8 arrays of the same H x W x 3."""
    xs, xd = npy_header(xp)
    ys, yd = npy_header(yp)
    for p, s, d, want in ((xp, xs, xd, np.float32), (yp, ys, yd, np.uint8)):
        if d != np.dtype(want) or len(s) != 3 or s[2] != 3:
            raise RunFolderError(
                f"{p}: damaged cached array: {d} {s}, expected {np.dtype(want)} H x W x 3; "
                f"{DATA_ADVICE}")
    if xs != ys:
        raise RunFolderError(
            f"{xp}: its shape {xs} differs from its target {yp.name}'s {ys}; {DATA_ADVICE}")
    if not values_in_unit_range(xp):
        raise RunFolderError(
            f"{xp}: damaged cached array: values that are not finite or outside [0, 1] (a run "
            f"writes neither); {DATA_ADVICE}")


def values_in_unit_range(path, rows=256):
    """Whether a float32 H x W x 3 ``.npy`` file holds finite values in [0, 1] only (read
    memory-mapped, ``rows`` rows at a time)."""
    a = np.load(path, mmap_mode="r", allow_pickle=False)
    for top in range(0, a.shape[0], rows):
        part = np.asarray(a[top:top + rows])
        if not (np.isfinite(part).all() and part.min(initial=0) >= 0
                and part.max(initial=0) <= 1):
            return False
    return True


def check_data(out):
    """Every complete cached pair under RUN/data (a target without its input is the trace of
    an interrupted write: it is made again): ``.in.npy`` input stores (pairs.check_cached)
    and inputs of the first format (``.x.npy``, migrated when used)."""
    for suffix in (".x.npy", ".in.npy"):
        for xp in sorted(pathlib.Path(out, "data").rglob("*" + suffix)):
            yp = xp.with_name(xp.name[: -len(suffix)] + ".y.npy")
            if not yp.is_file():
                raise RunFolderError(f"{xp}: its target {yp.name} is missing; {DATA_ADVICE}")
            try:
                if suffix == ".x.npy":
                    check_pair(xp, yp)
                else:
                    check_cached(xp, yp)
            except ValueError as e:
                raise RunFolderError(f"{e}; {DATA_ADVICE}") from None


def check_checkpoints(out, uid, model_dir, epochs):
    """The checkpoints of a unit that is not done: ``last.pt`` resumable, ``best.pt``
    loadable; returns the epochs ``last.pt`` holds (0 without it)."""
    advice = (f"no earlier checkpoint is kept to fall back to; "
              f"{unit_advice(out, uid)}")
    model_dir = pathlib.Path(model_dir)
    if model_dir.exists() and not model_dir.is_dir():
        raise RunFolderError(f"{model_dir}: not a folder of checkpoints; {unit_advice(out, uid)}")
    if (model_dir / "last.pt").is_file() and not (model_dir / "best.pt").is_file():
        raise RunFolderError(
            f"{model_dir / 'best.pt'}: missing beside last.pt (the trainer writes it first); "
            f"{advice}")
    done = 0
    for name, keys in (("last.pt", RESUME_STATE), ("best.pt", ("model", "config"))):
        path = model_dir / name
        if not path.is_file():
            continue
        try:
            ck = load_checkpoint(str(path), keys=keys)
        except CheckpointError as e:
            raise RunFolderError(f"{e}; {advice}") from None
        if name == "last.pt":
            e = ck["epoch"]
            if isinstance(e, bool) or not isinstance(e, int) or not 0 <= e < epochs:
                raise RunFolderError(
                    f"{path}: damaged checkpoint: epoch {e!r} is not one of 0..{epochs - 1}; "
                    f"{advice}")
            done = e + 1
    return done
