"""Uncertainty of the experiment's tables (docs/experiment.md, "How sure the numbers are"):
a seeded bootstrap over the test scenes, and over the training seeds when a run has several,
with a Student-t interval where the percentile interval is too narrow (numpy only).

The data of one row, input and metric is an array ``v`` of shape (seeds, scenes): the score
of each test scene (in a fixed order) under each training seed, and ``weights``, one per
scene, that make the weighted mean the table's mean: a per-fold row's score is the mean of
its folds' means (the paper's), so a scene of fold k weighs n / (K n_k); a row tested on
every scene weighs each scene 1. Every scene's value is the score of the model that did not
see it (a per-fold row: its fold's model), so the scenes are one sample of n observations:

- a replicate draws the n scenes with replacement across the whole test set (not within
  folds: a fold of one or two scenes would make the interval collapse to zero width) and,
  with more than one seed, the seeds (crossed: every seed is tested on every scene); its
  statistic is the weighted mean over the drawn seeds x drawn scenes (the weights normalised
  over the drawn scenes);
- the interval is the wider, on each side, of the replicates' 2.5th and 97.5th percentiles
  and the Student-t interval mean +- t(df) SE, where SE^2 = V_scenes n / (n - 1) +
  V_seeds m / (m - 1) (the replicates' variance with only the scenes, resp. only the m
  seeds, drawn, each corrected for the bootstrap's plug-in variance) and df the
  Welch-Satterthwaite degrees of freedom of the two parts (n - 1 with one seed). The
  percentile interval alone covers the truth in far fewer than 95 % of repetitions at n = 4
  to 12 (it never reaches past the sample's extremes); the t interval holds its level for
  normal scene scores (the simulation in python/tests/test_experiment_coverage.py).

A comparison is the paired difference of two rows (the same scenes and draws, the same seed
index when both have the seeds; a row with one series, e.g. the burst row, is paired with
each seed of the other): each replicate's statistic is the difference of the two rows'
weighted means. Its verdict: "better" or "worse" when the 95 % interval excludes 0 (PSNR and
SSIM: higher is better; Delta E: lower), else "not distinguishable".

No interval (null), with a ``note`` saying why, and no verdict (null), when there are fewer
than :data:`MIN_SCENES` test scenes, or a fold of a per-fold row holds fewer than
:data:`MIN_PER_FOLD` ("too few scenes for an interval"); also (verdict "not
distinguishable") when a value is infinite or undefined (the PSNR of a prediction identical
to its target: the mean is "inf", "-inf" or "nan", the strings table.json uses) or too large
to average. No zero-width interval comes from resampling a single value, no numpy warning is
raised and no NaN is returned for finite input."""

import functools
import math

import numpy as np

from . import tdist

REPLICATES = 10_000
#: A mean or bound within this much (relative to the values) of 0 is 0: the rounding of the
#: per-fold weights never decides a verdict.
ROUNDING = 1e-12
LEVEL = 0.95
#: Fewest test scenes of an interval, and fewest test scenes of each fold of a per-fold row.
MIN_SCENES = 3
MIN_PER_FOLD = 2
#: Values beyond this magnitude are not averaged into an interval (their squares overflow).
HUGE = 1e100
HIGHER_IS_BETTER = {"psnr": True, "ssim": True, "delta_e": False}
METHOD = ("bootstrap of the mean over the test scenes (each scene's score from the model that "
          "did not see it; scenes resampled across the whole test set) and over the training "
          "seeds when there are several (crossed); the interval is the wider of the "
          "percentile interval and the Student-t interval with the bootstrap's standard "
          "error (Welch-Satterthwaite degrees of freedom); paired differences for gains and "
          "comparisons")
NO_INTERVAL = ("a test scene's value is infinite or undefined (e.g. the PSNR of a prediction "
               "identical to its target): no interval")
TOO_FEW = "too few scenes for an interval"
TOO_LARGE = "values too large to average: no interval"


def bootstrap_seed(seed):
    """The bootstrap's seed of a run made with ``--seed seed`` (fixed, so a table's intervals
    are the same on every rerun)."""
    return (int(seed) * 1_000_003 + 41) % 2**32


def _counts(rng, n, replicates):
    """How often each of ``n`` items is drawn per replicate ((replicates, n), as floats)."""
    return rng.multinomial(n, np.full(n, 1.0 / n), size=replicates).astype(np.float64)


@functools.lru_cache(maxsize=16)
def _draws(seed, n, n_seeds, replicates):
    """The (scene counts, seed counts or None) of the replicates of ``seed``: the same draws
    for every row, input and metric of a table (so pairs and rows share them)."""
    rng = np.random.default_rng(seed)
    scenes = _counts(rng, n, replicates)
    seeds = _counts(rng, n_seeds, replicates) if n_seeds > 1 else None
    return scenes, seeds


def _as_2d(v):
    v = np.asarray(v, dtype=np.float64)
    return v.reshape(1, -1) if v.ndim < 2 else v


def _weights(w, n):
    w = np.ones(n) if w is None else np.asarray(w, dtype=np.float64)
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError(f"{w.size} scene weights for {n} scenes (each positive)")
    return w / w.mean()


def _side_stat(v, w, scenes, seeds):
    """The weighted mean of one row ``v`` (seeds x scenes, centred) per replicate:
    ``scenes``, ``seeds``: the draws' counts (None: every item once)."""
    n_seeds, n = v.shape
    cw = w[None, :] if scenes is None else scenes * w
    if n_seeds == 1 or seeds is None:
        per_scene = v.mean(axis=0)[None, :]
    else:
        per_scene = seeds @ v / seeds.sum(axis=1, keepdims=True)
    return (per_scene * cw).sum(axis=1) / cw.sum(axis=1)


def _replicates(sides, scenes, seeds):
    """The statistic sum(sign x weighted mean) of ``sides`` [(v, w, sign)] per replicate."""
    return sum(sign * _side_stat(v, w, scenes, seeds) for v, w, sign in sides)


def _point(sides):
    return sum(sign * float((v.mean(axis=0) * w).sum() / w.sum()) for v, w, sign in sides)


def replicates_of(v, weights=None, seed=0, replicates=REPLICATES):
    """The bootstrap replicates (a float array) of the weighted mean of ``v`` (seeds x
    scenes, finite): scenes drawn across the test set, seeds drawn when there are more than
    one."""
    v = _as_2d(v)
    c = v.flat[0]  # centred: a constant gives exactly that constant
    scenes, seeds = _draws(int(seed), v.shape[1], v.shape[0], int(replicates))
    return c + _replicates([(v - c, _weights(weights, v.shape[1]), 1.0)], scenes, seeds)


def _nonfinite_mean(v):
    """The mean of an array holding inf or nan, without numpy's warnings."""
    has_pos, has_neg = bool(np.any(v == np.inf)), bool(np.any(v == -np.inf))
    if np.any(np.isnan(v)) or (has_pos and has_neg):
        return "nan"
    return "inf" if has_pos else "-inf"


def _finite_or_text(x):
    x = float(x)
    return x if math.isfinite(x) else _nonfinite_mean(np.array([x]))


def _scaled_means(sides):
    """(mean, per-seed means) of ``sides`` [(v, w, sign)] of finite values of any magnitude:
    computed on the values divided by their largest magnitude (no overflow on the way)."""
    s = max(float(np.max(np.abs(v), initial=0.0)) for v, _, _ in sides) or 1.0
    with np.errstate(over="ignore", invalid="ignore"):
        per_seed = sum(sign * ((v / s) @ w) / w.sum() for v, w, sign in sides) * s
        mean = sum(sign * float(((v / s).mean(axis=0) @ w) / w.sum()) for v, w, sign in sides)
        mean *= s
    return _finite_or_text(mean), [_finite_or_text(x) for x in np.atleast_1d(per_seed)]


def _too_few(n, folds):
    """Whether ``n`` scenes in ``folds`` (a fold label per scene, or None) are too few."""
    if n < MIN_SCENES:
        return True
    if folds is None:
        return False
    _, counts = np.unique(np.asarray(folds), return_counts=True)
    return bool(np.any(counts < MIN_PER_FOLD))


def _bounds(sides, point, seed, replicates, level):
    """(ci_low, ci_high) of the centred ``sides`` about ``point`` (module docstring)."""
    n = sides[0][0].shape[1]
    m = max(v.shape[0] for v, _, _ in sides)
    scenes, seeds = _draws(int(seed), n, m, int(replicates))
    joint = _replicates(sides, scenes, seeds)
    lo, hi = (float(x) for x in np.quantile(joint, [(1 - level) / 2, (1 + level) / 2]))
    var_sc = float(np.var(_replicates(sides, scenes, None))) * n / (n - 1)
    var_sd = 0.0 if seeds is None else \
        float(np.var(_replicates(sides, None, seeds))) * m / (m - 1)
    var = var_sc + var_sd
    if var > 0:
        a, b = var_sc / var, var_sd / var  # (shares: no overflow)
        df = 1.0 / (a * a / (n - 1) + (b * b / (m - 1) if m > 1 else 0.0))
        half = tdist.quantile(level, df) * math.sqrt(var)
        lo, hi = min(lo, point - half), max(hi, point + half)
    return lo, hi


def _summarise(sides, values, folds, seed, replicates, level):
    """The summary of ``sides`` [(v, weights, sign)] whose per-scene values (seeds x scenes,
    for the non-finite checks) are ``values``."""
    n_seeds, n = values.shape
    out = {"n_scenes": int(n)}
    if n == 0 or n_seeds == 0:
        return {**out, "mean": None, "ci_low": None, "ci_high": None, "seed_means": [],
                "seed_sd": None, "note": "no test scenes" if n == 0 else "no seeds"}
    if not np.all(np.isfinite(values)):
        means = [float(np.mean(x)) if np.all(np.isfinite(x)) else _nonfinite_mean(x)
                 for x in values]
        return {**out, "mean": _nonfinite_mean(values), "ci_low": None, "ci_high": None,
                "seed_means": means, "seed_sd": None, "note": NO_INTERVAL}
    sides = [(_as_2d(v), _weights(w, n), float(sign)) for v, w, sign in sides]
    big = max(float(np.max(np.abs(v))) for v, _, _ in sides)
    if big > HUGE or _too_few(n, folds):
        mean, seed_means = _scaled_means(sides)
        return {**out, "mean": mean, "ci_low": None, "ci_high": None, "seed_means": seed_means,
                "seed_sd": None, "note": TOO_LARGE if big > HUGE else TOO_FEW}
    offset = sum(sign * v.flat[0] for v, _, sign in sides)
    centred = [(v - v.flat[0], w, sign) for v, w, sign in sides]
    point = _point(centred)
    lo, hi = _bounds(centred, point, seed, replicates, level)
    centred_means = np.atleast_1d(sum(sign * (v @ w) / w.sum() for v, w, sign in centred))
    seed_means = offset + centred_means
    # rounding: the per-fold weights can make an exact 0 a -1e-17 (tested)
    tol = ROUNDING * (1.0 + big)
    lo, hi, mean = (0.0 if abs(x) <= tol else float(x)
                    for x in (offset + lo, offset + hi, offset + point))
    return {**out, "mean": mean, "ci_low": lo, "ci_high": hi,
            "seed_means": [float(x) for x in seed_means],
            "seed_sd": float(np.std(centred_means, ddof=1)) if len(seed_means) > 1 else None}


def summary(v, folds=None, weights=None, seed=0, replicates=REPLICATES, level=LEVEL):
    """{"mean", "ci_low", "ci_high", "n_scenes", "seed_means", "seed_sd"} of ``v`` (seeds x
    scenes) with the scenes' ``weights`` (None: equal); ``folds``: each scene's fold, for a
    per-fold row (a fold of fewer than MIN_PER_FOLD scenes: no interval). Without an
    interval: ``ci_low`` and ``ci_high`` None and a "note" saying why."""
    v = _as_2d(v)
    return _summarise([(v, weights, 1.0)], v, folds, seed, replicates, level)


def paired(a, b):
    """Per-scene differences ``a - b`` of two (seeds x scenes) arrays, paired by scene and by
    seed index (a one-seed side is paired with each seed of the other); the scene counts
    must agree. Differences of non-finite values stay non-finite (inf - inf: nan) without a
    warning."""
    a, b = _as_2d(a), _as_2d(b)
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


def compare(a, b, metric, folds=None, weights=(None, None), seed=0, replicates=REPLICATES,
            level=LEVEL):
    """The paired difference ``a - b`` (:func:`paired`; ``weights``: each side's scene
    weights) summarised like :func:`summary`, with its ``verdict`` (None: too few scenes)."""
    a, b = _as_2d(a), _as_2d(b)
    if 0 in (a.shape[0], b.shape[0]):  # no seeds: nothing to pair
        d = np.zeros((0, a.shape[1]))
        return {**_summarise([(d, None, 1.0)], d, None, seed, replicates, level),
                "verdict": "not distinguishable"}
    d = paired(a, b)
    wa, wb = weights
    same = (wa is None and wb is None) or (
        wa is not None and wb is not None and np.array_equal(np.asarray(wa), np.asarray(wb)))
    sides = [(d, wa, 1.0)] if same else [(a, wa, 1.0), (b, wb, -1.0)]
    s = _summarise(sides, d, folds, seed, replicates, level)
    v = None if s.get("note") == TOO_FEW else verdict(s["ci_low"], s["ci_high"], metric)
    return {**s, "verdict": v}
