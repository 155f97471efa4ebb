"""What a unit's scores.json may hold (runfolder.read_scores, docs/experiment.md "A damaged
run folder"): each value of the range its metric can give, and a training history and
initial validation that the table, the curves and TensorBoard can draw.

- ``psnr``: a number in [0, :data:`PSNR_MAX`] dB, or ``"inf"`` (a prediction identical to
  its target). The scores are of 8-bit images: the mean squared error is at most 255^2 (0
  dB), and the smallest non-zero one, one sample off by 1 in N, gives 48.1 + 10 log10(N) dB,
  133 dB for a 100-megapixel image: 200 dB is past any finite score.
- ``ssim``: a number in [-1, 1] (SSIM's range).
- ``delta_e``: a number in [0, :data:`DELTA_E_MAX`] (CIEDE2000 between display colours
  stays below about 120; 200 leaves room).
- ``history``: a list of objects, each with an integer ``epoch`` (0 to the run's
  ``--epochs`` - 1, or below :data:`EPOCH_MAX` when the run's is not known), strictly
  increasing; every other value a number of magnitude at most :data:`HISTORY_MAX` (losses
  at least 0) or one of "inf", "-inf", "nan" (a diverged epoch: not drawn).
- ``initial``: an object (empty for the untrained row) of such values, or absent."""

import math

NON_FINITE = ("inf", "-inf", "nan")
PSNR_MAX = 200.0
DELTA_E_MAX = 200.0
#: The range of each metric's finite values, and the strings it may hold instead.
METRICS = {"psnr": ((0.0, PSNR_MAX), ("inf",)), "ssim": ((-1.0, 1.0), ()),
           "delta_e": ((0.0, DELTA_E_MAX), ())}
EPOCH_MAX = 10**6
HISTORY_MAX = 1e6
#: History and initial values that are losses (never negative).
LOSSES = ("loss", "val_loss")


def _number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def score_problem(metric, v):
    """Why ``v`` cannot be the ``metric`` of an image (a string), or None."""
    (lo, hi), texts = METRICS[metric]
    if isinstance(v, str) and v in texts:
        return None
    if not _number(v) or not math.isfinite(v) or not lo <= v <= hi:
        return (f"{metric} {str(v)[:40]} is not a {metric} score (a number in "
                f"[{lo:g}, {hi:g}]{', or inf' if texts else ''})")
    return None


def _value_problem(key, v, where):
    if isinstance(v, str) and v in NON_FINITE:
        return None
    low = 0.0 if key in LOSSES else -HISTORY_MAX
    if not _number(v) or not math.isfinite(v) or not low <= v <= HISTORY_MAX:
        return (f"{where} {key} is {str(v)[:40]}, not a number in [{low:g}, {HISTORY_MAX:g}] "
                "or inf/nan")
    return None


def _values_problem(d, where):
    for k, v in d.items():
        why = _value_problem(k, v, where)
        if why:
            return why
    return None


def history_problem(history, epochs=None):
    """Why ``history`` is not a unit's training history (a string), or None; ``epochs``:
    the run's ``--epochs`` (the bound of an epoch's number)."""
    if not isinstance(history, list):
        return "no history list"
    top = EPOCH_MAX if epochs is None else int(epochs)
    last = -1
    for h in history:
        if not isinstance(h, dict):
            return f"a history entry that is not an object: {str(h)[:60]}"
        e = h.get("epoch")
        # a whole number: scores.json stores it as a float (unit._num), 0.0, 1.0, ...
        whole = isinstance(e, int) or isinstance(e, float) and e.is_integer()
        if isinstance(e, bool) or not whole or not 0 <= e < top:
            return (f"a history entry whose epoch is {str(e)[:40]}, not a whole number from 0 "
                    f"to {top - 1}")
        if e <= last:
            return f"history epochs not strictly increasing ({last} then {e})"
        last = e
        why = _values_problem({k: v for k, v in h.items() if k != "epoch"},
                              f"history epoch {e}:")
        if why:
            return why
    return None


def initial_problem(initial):
    """Why ``initial`` is not the untrained weights' validation (a string), or None."""
    if initial is None:  # a scores.json written before the curves: no initial
        return None
    if not isinstance(initial, dict):
        return f"its initial is {str(initial)[:40]}, not an object"
    return _values_problem(initial, "initial:")
