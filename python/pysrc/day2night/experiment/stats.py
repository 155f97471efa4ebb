"""Uncertainty of the experiment's tables (docs/experiment.md, "How sure the numbers are"):
a seeded percentile bootstrap over the test scenes, stratified by fold, and over the training
seeds when a run has several (numpy only).

The data of one row, input and metric is an array ``v`` of shape (seeds, scenes): the score of
each test scene (in a fixed order) under each training seed. ``strata`` gives each scene's
fold (the fold whose test split holds it). A replicate draws, independently and with
replacement, the scenes within each fold (a fold keeps its number of scenes; a scene never
moves to another fold) and, with more than one seed, the seeds; its statistic is the mean of
``v`` over the drawn seeds x drawn scenes (seeds and scenes are crossed: every seed is tested
on every scene). The interval is the replicates' 2.5th and 97.5th percentiles.

A row's value per scene is weighted (``weights``) so that its mean is the table's: a per-fold
row's score is the mean of its folds' means (the paper's), so a scene of fold k counts
n / (K n_k); a row tested on every scene weighs each scene 1. Resampling within folds keeps
these weights, so the bootstrap's statistic is always the table's.

A comparison is the paired per-scene difference of two rows (the same scene, and the same
seed index when both have the seeds; a row with one series, e.g. the burst row, is paired
with each seed of the other), bootstrapped the same way. Its verdict: "better" or "worse"
when the 95 % interval excludes 0 (PSNR and SSIM: higher is better; Delta E: lower), else
"not distinguishable".

An infinite or undefined per-scene value (the PSNR of a prediction identical to its target)
has no interval: the mean is "inf", "-inf" or "nan" (the strings table.json uses), the
interval null, and a ``note`` says why; no numpy warning is raised."""

import functools

import numpy as np

REPLICATES = 10_000
#: A mean or bound within this much (relative to the values) of 0 is 0: the rounding of the
#: per-fold weights never decides a verdict.
ROUNDING = 1e-12
LEVEL = 0.95
HIGHER_IS_BETTER = {"psnr": True, "ssim": True, "delta_e": False}
METHOD = ("percentile bootstrap of the mean over the test scenes, resampled within their "
          "folds, and over the training seeds when there are several (crossed); paired "
          "per-scene differences for gains and comparisons")
NO_INTERVAL = ("a test scene's value is infinite or undefined (e.g. the PSNR of a prediction "
               "identical to its target): no interval")


def bootstrap_seed(seed):
    """The bootstrap's seed of a run made with ``--seed seed`` (fixed, so a table's intervals
    are the same on every rerun)."""
    return (int(seed) * 1_000_003 + 41) % 2**32


def _counts(rng, n, replicates, strata=None):
    """How often each of ``n`` items is drawn per replicate ((replicates, n) ints, as
    floats), drawn within each stratum (``strata``: one label per item; None: one)."""
    strata = np.zeros(n, dtype=np.int64) if strata is None else np.asarray(strata)
    if strata.shape != (n,):
        raise ValueError(f"{strata.size} fold labels for {n} scenes")
    out = np.zeros((replicates, n), dtype=np.float64)
    for s in sorted(set(strata.tolist())):
        idx = np.flatnonzero(strata == s)
        m = len(idx)
        out[:, idx] = rng.multinomial(m, np.full(m, 1.0 / m), size=replicates)
    return out


def _nonfinite_mean(v):
    """The mean of an array holding inf or nan, without numpy's warnings."""
    has_pos, has_neg = bool(np.any(v == np.inf)), bool(np.any(v == -np.inf))
    if np.any(np.isnan(v)) or (has_pos and has_neg):
        return "nan"
    return "inf" if has_pos else "-inf"


def replicates_of(v, strata=None, seed=0, replicates=REPLICATES):
    """The bootstrap replicates (a float array) of the mean of ``v`` (seeds x scenes, finite):
    scenes drawn within ``strata``, seeds drawn when there are more than one."""
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    n_seeds, n = v.shape
    labels = None if strata is None else tuple(np.asarray(strata).tolist())
    scenes, seeds = _draws(int(seed), n, n_seeds, int(replicates), labels)
    c = v.flat[0]  # centred: a constant gives exactly that constant
    d = v - c
    if n_seeds == 1:
        return c + scenes @ d[0] / n
    return c + ((seeds @ d) * scenes).sum(axis=1) / (n_seeds * n)


@functools.lru_cache(maxsize=16)
def _draws(seed, n, n_seeds, replicates, strata):
    """The (scene counts, seed counts or None) of the replicates of ``seed``: the same draws
    for every row, input and metric of a table (so pairs and rows share them)."""
    rng = np.random.default_rng(seed)
    scenes = _counts(rng, n, replicates, None if strata is None else np.asarray(strata))
    seeds = _counts(rng, n_seeds, replicates) if n_seeds > 1 else None
    return scenes, seeds


def summary(v, strata=None, seed=0, replicates=REPLICATES, level=LEVEL):
    """{"mean", "ci_low", "ci_high", "n_scenes", "seed_means", "seed_sd"} of ``v`` (seeds x
    scenes; non-finite values: no interval, a "note")."""
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    n_seeds, n = v.shape
    out = {"n_scenes": int(n)}
    if n == 0:
        return {**out, "mean": None, "ci_low": None, "ci_high": None, "seed_means": [],
                "seed_sd": None, "note": "no test scenes"}
    if not np.all(np.isfinite(v)):
        means = [float(np.mean(x)) if np.all(np.isfinite(x)) else _nonfinite_mean(x)
                 for x in v]
        return {**out, "mean": _nonfinite_mean(v), "ci_low": None, "ci_high": None,
                "seed_means": means, "seed_sd": None, "note": NO_INTERVAL}
    reps = replicates_of(v, strata, seed, replicates)
    lo, hi = np.quantile(reps, [(1 - level) / 2, (1 + level) / 2])
    c = v.flat[0]
    seed_means = c + (v - c).mean(axis=1)
    # rounding: a per-fold row's weighted values can make an exact 0 a -1e-17 (tested)
    tol = ROUNDING * (1.0 + float(np.max(np.abs(v))))
    lo, hi, mean = (0.0 if abs(x) <= tol else float(x) for x in (lo, hi, c + (v - c).mean()))
    return {**out, "mean": mean, "ci_low": lo, "ci_high": hi,
            "seed_means": [float(x) for x in seed_means],
            "seed_sd": float(np.std(seed_means, ddof=1)) if n_seeds > 1 else None}


def paired(a, b):
    """Per-scene differences ``a - b`` of two (seeds x scenes) arrays, paired by scene and by
    seed index (a one-seed side is paired with each seed of the other); the scene counts
    must agree. Differences of non-finite values stay non-finite (inf - inf: nan) without a
    warning."""
    a = np.atleast_2d(np.asarray(a, dtype=np.float64))
    b = np.atleast_2d(np.asarray(b, dtype=np.float64))
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"paired rows have {a.shape[1]} and {b.shape[1]} scenes")
    if a.shape[0] != b.shape[0] and 1 not in (a.shape[0], b.shape[0]):
        raise ValueError(f"paired rows have {a.shape[0]} and {b.shape[0]} seeds")
    with np.errstate(invalid="ignore", over="ignore"):
        return a - b


def verdict(ci_low, ci_high, metric):
    """"better", "worse" or "not distinguishable": a difference row - reference whose
    interval excludes 0 (the direction by ``metric``: Delta E is better lower)."""
    if ci_low is None or ci_high is None:
        return "not distinguishable"
    if ci_low > 0:
        return "better" if HIGHER_IS_BETTER[metric] else "worse"
    if ci_high < 0:
        return "worse" if HIGHER_IS_BETTER[metric] else "better"
    return "not distinguishable"


def compare(a, b, metric, strata=None, seed=0, replicates=REPLICATES, level=LEVEL):
    """The paired difference ``a - b`` (:func:`paired`) summarised (:func:`summary`) with
    its ``verdict``."""
    s = summary(paired(a, b), strata, seed, replicates, level)
    return {**s, "verdict": verdict(s["ci_low"], s["ci_high"], metric)}
