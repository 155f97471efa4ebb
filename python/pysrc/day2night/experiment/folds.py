"""K-fold cross-validation over real night scenes (the paper's Sec. 5 "Supervised" rows).

The scenes are shuffled by a seeded permutation and cut into ``folds`` disjoint test folds
that together cover every scene (sizes differ by at most one). For fold ``i`` the other
scenes form its training part; a seeded draw takes ``val`` of them for validation and the
rest train. With the paper's 105 scenes and 3 folds: 60 train / 10 validation / 35 test.

Every list in the manifest is sorted by scene id, so positions are stable (the noisy task
alternates ISOs by position, and the mix's permutation indexes the training list).
The permutations come from ``numpy.random.RandomState`` (the release's generator, whose
stream numpy keeps fixed across versions).
"""

import collections
import json

import numpy as np

from ..atomic import write_json

FORMAT = "day2night-folds/1"


class FoldError(ValueError):
    """A fold request the real set cannot satisfy (the message names the numbers)."""


def default_val(train_part: int) -> int:
    """Validation scenes of a fold's training part: one in seven (10 of 70, the paper's)."""
    return max(1, int(round(train_part / 7)))


def _check_count(ids, folds):
    """``folds`` as an int, else FoldError: not an integer, under 2, more than the scenes,
    or duplicate scene ids."""
    if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)):
        raise FoldError(f"folds must be an integer, got {folds!r}")
    folds = int(folds)
    if folds < 2:
        raise FoldError(f"folds = {folds}: cross-validation needs at least 2 folds")
    count = collections.Counter(ids)
    dup = sorted(s for s, n in count.items() if n > 1)
    if dup:
        raise FoldError(f"scene ids appear more than once in the real set: {', '.join(dup)}")
    if folds > len(ids):
        raise FoldError(
            f"{folds} folds need at least {folds} scenes (one per test fold); "
            f"the real set has {len(ids)}"
        )
    return folds


def make_folds(scenes, folds=3, seed=0, val=None):
    """The k-fold manifest (a dict) over ``scenes`` (scene ids, any order).

    ``val``: validation scenes per fold (default: :func:`default_val` of the training part).
    Raises :class:`FoldError` for fewer than 2 folds, more folds than scenes, duplicate ids,
    or a real set too small to leave every fold at least one training and one validation
    scene."""
    ids = [str(s) for s in scenes]
    folds = _check_count(ids, folds)
    n = len(ids)
    ids.sort()
    sizes = [n // folds + (1 if i < n % folds else 0) for i in range(folds)]
    smallest_part = n - max(sizes)
    need_val = default_val(smallest_part) if val is None else int(val)
    if val is not None and (isinstance(val, bool) or need_val < 1):
        raise FoldError(f"val = {val!r}: each fold needs at least 1 validation scene")
    if smallest_part < need_val + 1:
        raise FoldError(
            f"the real set ({n} scenes) is too small for {folds} folds: a fold's training "
            f"part has {smallest_part} scenes, it needs {need_val} for validation and at "
            f"least 1 for training"
        )
    rng = np.random.RandomState(seed)
    perm = rng.permutation(n)
    out = []
    start = 0
    for i, size in enumerate(sizes):
        test_idx = set(int(j) for j in perm[start : start + size])
        start += size
        rest = [j for j in range(n) if j not in test_idx]
        v = default_val(len(rest)) if val is None else int(val)
        pick = rng.permutation(len(rest))[:v]
        val_idx = set(rest[int(k)] for k in pick)
        out.append(
            {
                "fold": i,
                "train": [ids[j] for j in rest if j not in val_idx],
                "val": sorted(ids[j] for j in val_idx),
                "test": sorted(ids[j] for j in test_idx),
            }
        )
    manifest = {
        "format": FORMAT,
        "seed": int(seed),
        "folds": folds,
        "scenes": ids,
        "splits": out,
    }
    check_folds(manifest)
    return manifest


def check_folds(manifest):
    """Assert a fold manifest's invariants (raises FoldError naming the fold and scene)."""
    if manifest.get("format") != FORMAT:
        raise FoldError(f"not a {FORMAT} manifest (format {manifest.get('format')!r})")
    scenes = list(manifest["scenes"])
    all_set = set(scenes)
    tested = []
    for s in manifest["splits"]:
        tr, va, te = set(s["train"]), set(s["val"]), set(s["test"])
        for a, b, what in ((tr, va, "train and val"), (tr, te, "train and test"),
                           (va, te, "val and test")):
            both = sorted(a & b)
            if both:
                raise FoldError(f"fold {s['fold']}: scene {both[0]} is in both {what}")
        if tr | va | te != all_set:
            odd = sorted((tr | va | te) ^ all_set)
            raise FoldError(f"fold {s['fold']}: scene {odd[0]} is missing or unknown")
        if not tr or not va or not te:
            raise FoldError(f"fold {s['fold']}: an empty train, val or test list")
        tested += s["test"]
    if sorted(tested) != sorted(scenes):
        count = collections.Counter(tested)
        dup = sorted(t for t, n in count.items() if n > 1)
        raise FoldError(
            f"test folds overlap or miss scenes (repeated: {dup[:3]}, "
            f"missing: {sorted(all_set - set(tested))[:3]})"
        )


def write_folds(path, manifest):
    """Write the manifest as JSON (temporary file + rename)."""
    check_folds(manifest)
    write_json(path, manifest)


def read_folds(path):
    """Read and check a fold manifest written by :func:`write_folds`."""
    try:
        with open(path, encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as e:
        raise FoldError(f"{path}: cannot read the fold manifest: {e}") from None
    try:
        check_folds(manifest)
    except (KeyError, TypeError) as e:
        raise FoldError(f"{path}: malformed fold manifest ({e})") from None
    except FoldError as e:
        raise FoldError(f"{path}: {e}") from None
    return manifest
