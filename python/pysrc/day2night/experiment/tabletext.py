"""What RUN/table.md (table.py) and RUN/index.html (report_tables.py) print alike: the
columns of each task's table, the rounding of every number, the interval cells, the seeds
count and the protocol sentence. One formatter, so the page and table.md never disagree.

Rounding: PSNR 2 decimals, SSIM and Delta E 4 (the paper's); a value that is not zero but
would print as zero at that rounding (a difference of -0.00004) is printed with 2 significant
digits instead (``-4e-05``), so an interval is never shown as ``[-0.0000, -0.0000]``."""

import math

from ..isos import NOISY_ISOS

#: (metric, name, decimals, +1 higher is better / -1 lower is better), in column order.
METRICS = (("psnr", "PSNR", 2, +1), ("ssim", "SSIM", 4, +1), ("delta_e", "Delta E", 4, -1))
DIGITS = {m: d for m, _, d, _ in METRICS}
NAMES = {m: n for m, n, _, _ in METRICS}
#: The metrics the paper reports per task (its number is shown beside these).
PAPER_METRICS = {"clean": ("psnr", "ssim", "delta_e"), "noisy": ("psnr", "ssim")}


def inputs_of(task):
    """The inputs each test scene is scored on: the merged raw, or each noisy ISO."""
    return ["clean"] if task == "clean" else [str(i) for i in NOISY_ISOS]


def input_name(key):
    """"merged raw" or "ISO 1600"."""
    return "merged raw" if key == "clean" else f"ISO {key}"


def columns(task):
    """[(input, metric)] of a task's table, in order: every input, every metric."""
    return [(k, m) for k in inputs_of(task) for m, _, _, _ in METRICS]


def num(v):
    """A float of a table.json number (the strings "inf", "-inf", "nan" too), or None."""
    if v is None or isinstance(v, bool):
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def fmt(v, digits, sign=False):
    """A number as both tables print it: "-" when absent, "inf"/"-inf"/"nan" as such,
    ``digits`` decimals (``sign``: a difference, always signed), 2 significant digits where
    that rounding would print a non-zero value as zero."""
    f = num(v)
    if f is None:
        return "-"
    if not math.isfinite(f):
        return "nan" if f != f else ("inf" if f > 0 else "-inf")
    plus = "+" if sign else ""
    s = f"{f:{plus}.{digits}f}"
    if f != 0 and float(s) == 0:
        return f"{f:{plus}.2g}"
    return s


def bounds(s, digits, sign=False):
    """``[low, high]`` of a summary (stats.py), or ``(why)`` when it has no interval."""
    if not isinstance(s, dict):
        return "-"
    if num(s.get("ci_low")) is None or num(s.get("ci_high")) is None:
        return f"({s.get('note') or 'no interval'})"
    return f"[{fmt(s['ci_low'], digits, sign)}, {fmt(s['ci_high'], digits, sign)}]"


def cell(s, digits, sign=False):
    """``mean [low, high]`` of a summary ("-" without one)."""
    if not isinstance(s, dict):
        return "-"
    return f"{fmt(s.get('mean'), digits, sign)} {bounds(s, digits, sign)}"


def seeds_count(seeds):
    """The "seeds" column: how many training seeds ("-" for a row without training)."""
    return "-" if not seeds else str(len(seeds))


def protocol_sentence(p):
    """The protocol of table.json's "protocol" as one sentence ("-" without one)."""
    if not p:
        return "-"
    folds = f"from {p['folds_file']}" if p.get("folds_file") else "seeded"
    return (f"{p.get('protocol', '-')} (targets {p.get('targets', '-')}, noise "
            f"{p.get('noise', '-')}, synthetic ISO {p.get('synth_iso', '-')}, folds {folds}); "
            f"AMP {p.get('amp') or 'off'}, channels-last "
            f"{'on' if p.get('channels_last') else 'off'}.")
