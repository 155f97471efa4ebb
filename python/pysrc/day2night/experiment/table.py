"""Tables 1 and 2 from the units' scores: RUN/table.json (every number per row, fold and
image) and RUN/table.md.

A unit's score per input (the merged raw, or ISO 1600 / 3200) is the mean over its test
images, as the release's test.py; a per-fold row's score is the mean of its folds' scores
(the paper's "three-fold cross validation"). PSNR of an identical prediction is infinite;
such a mean is reported as "inf"."""

import math
import pathlib

from ..isos import NOISY_ISOS
from ..atomic import write_json, write_text
from .burst import read_left_out
from .rows import of_task, select, tasks_of, test_keys
from .rows import units as row_units
from .runfolder import read_scores

METRICS = ("psnr", "ssim", "delta_e")
PAPER = {
    "clean": {
        "day": (41.16, 0.9713, 1.2369),
        "dimmed": (42.39, 0.9832, 1.0865),
        "global": (43.56, 0.9860, 0.9653),
        "ours": (45.28, 0.9893, 0.8759),
        "mix5": (45.99, 0.9887, 0.8682),
        "mix10": (46.01, 0.9890, 0.8559),
        "supervised": (46.19, 0.9895, 0.8605),
    },
    "noisy": {
        "day": (36.10, 0.9215, 33.55, 0.8960),
        "dimmed": (36.13, 0.9254, 33.47, 0.8969),
        "global": (36.84, 0.9353, 35.63, 0.9162),
        "ours": (37.41, 0.9368, 35.70, 0.9142),
        "mix5": (38.32, 0.9419, 36.60, 0.9206),
        "mix10": (39.04, 0.9477, 37.54, 0.9352),
        "supervised": (39.74, 0.9541, 38.16, 0.9419),
        # the supplementary's burst denoising (mean of the high-ISO frames)
        "burst": (34.91, 0.8021, 31.39, 0.6526),
    },
}


def _mean(values):
    vals = [float(v) for v in values]  # "inf"/"nan" strings too
    if not vals:
        return None
    m = math.fsum(vals) / len(vals)
    if math.isinf(m):
        return "inf" if m > 0 else "-inf"
    if math.isnan(m):
        return "nan"
    return m


def _unit_means(u, task):
    """A unit's mean score per input over its test images (its ``mean``)."""
    return {
        str(k): {m: _mean(i[m] for i in u["images"] if i["input"] == str(k)) for m in METRICS}
        for k in test_keys(task)
    }


def build(config, out, splits, n_scenes, n_days):
    """table.json of a run: ``config`` its resolved ExperimentConfig (tasks, rows, the
    record), ``out`` its folder (the units' scores.json), ``splits`` the fold manifest's,
    ``n_scenes`` and ``n_days`` the real scenes and day images it ran on."""
    rows_out = []
    left_out = read_left_out(out)
    gone = {(g["task"], g["row"]) for g in left_out}
    for task in tasks_of(config.task):
        for row in of_task(select(list(config.rows)), task):
            if (task, row.id) in gone:
                continue
            units = []
            for fold, _ in row_units(row, splits):
                path = pathlib.Path(out) / "units" / task / row.id / fold / "scores.json"
                units.append(read_scores(out, path, task, row.id, fold, test_keys(task)))
            for u in units:
                u["mean"] = _unit_means(u, task)
            mean = {
                str(k): {m: _mean(u["mean"][str(k)][m] for u in units) for m in METRICS}
                for k in test_keys(task)
            }
            rows_out.append(
                {"task": task, "row": row.id, "label": row.label, "units": units, "mean": mean}
            )
    return {
        "format": "day2night-experiment-table/1",
        "config": config.record(),
        "smoke": config.smoke,
        "not_the_paper": deviations(config, n_scenes, n_days),
        "folds": splits,
        "rows": rows_out,
        "left_out": left_out,
    }


def deviations(config, n_scenes, n_days):
    """How this run differs from the paper's protocol (said above its table)."""
    d = []
    if config.width != 32:
        d.append(f"UNet width {config.width} (paper: 32)")
    if config.epochs != 500:
        d.append(f"{config.epochs} epochs (paper: 500)")
    if n_scenes != 105:
        d.append(f"{n_scenes} real scenes (paper: 105)")
    if n_days != 70:
        d.append(f"{n_days} day images (paper: 70)")
    if config.folds != 3:
        d.append(f"{config.folds} folds (paper: 3)")
    return d


def _fmt(v, digits):
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    return f"{v:.{digits}f}"


def markdown(t):
    cfg = t["config"]
    lines = ["# day2night experiment: Tables 1 and 2", ""]
    if t["smoke"]:
        lines += [
            f"**Smoke run**: network width {cfg['width']} (the paper's UNet: 32). "
            "These are not the paper's numbers.",
            "",
        ]
    if t["not_the_paper"]:
        lines += ["Differs from the paper's protocol: " + "; ".join(t["not_the_paper"]) + ".", ""]
    lines += [
        f"Options: task {cfg['task']}, epochs {cfg['epochs']}, seed {cfg['seed']}, "
        f"folds {cfg['folds']}, width {cfg['width']}, device {cfg['device']}.",
        "Rows trained on synthesis only are tested on every real scene; rows with real data "
        "are the mean over the folds of each fold's test scenes.",
        "",
    ]
    by_task = {}
    for r in t["rows"]:
        by_task.setdefault(r["task"], []).append(r)
    if "clean" in by_task:
        lines += ["## Table 1: clean (ISO 50 merged raw input)", "",
                  "| model | PSNR | SSIM | Delta E | paper PSNR / SSIM / Delta E |",
                  "|---|---|---|---|---|"]
        for r in by_task["clean"]:
            m = r["mean"]["clean"]
            p = PAPER["clean"].get(r["row"])
            ps = f"{p[0]:.2f} / {p[1]:.4f} / {p[2]:.4f}" if p else "-"
            lines.append(f"| {r['label']} | {_fmt(m['psnr'], 2)} | {_fmt(m['ssim'], 4)} | "
                         f"{_fmt(m['delta_e'], 4)} | {ps} |")
        lines.append("")
    if "noisy" in by_task:
        lo, hi = NOISY_ISOS
        lines += [f"## Table 2: noisy (first frame at ISO {lo} and {hi})", "",
                  f"| model | ISO {lo} PSNR | ISO {lo} SSIM | ISO {hi} PSNR | ISO {hi} SSIM | "
                  "paper (same columns) |", "|---|---|---|---|---|---|"]
        for r in by_task["noisy"]:
            a, b = (r["mean"][str(iso)] for iso in NOISY_ISOS)
            p = PAPER["noisy"].get(r["row"])
            ps = f"{p[0]:.2f} / {p[1]:.4f} / {p[2]:.2f} / {p[3]:.4f}" if p else "-"
            lines.append(f"| {r['label']} | {_fmt(a['psnr'], 2)} | {_fmt(a['ssim'], 4)} | "
                         f"{_fmt(b['psnr'], 2)} | {_fmt(b['ssim'], 4)} | {ps} |")
        lines.append("")
    for g in t.get("left_out", []):
        lines.append(f"Left out: the {g['row']} row of the {g['task']} task: {g['why']}.")
    lines.append("Per row, fold and image: table.json. Test scenes: index.html.")
    return "\n".join(lines) + "\n"


def write(out, t):
    """RUN/table.json and RUN/table.md of the table ``t`` (:func:`build`'s)."""
    write_json(pathlib.Path(out) / "table.json", t)
    write_text(pathlib.Path(out) / "table.md", markdown(t))
