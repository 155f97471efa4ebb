"""Tables 1 and 2 from the units' scores: RUN/table.json (every number per row, fold and
image) and RUN/table.md.

A unit's score per input (the merged raw, or ISO 1600 / 3200) is the mean over its test
images, as the release's test.py; a per-fold row's score is the mean of its folds' scores
(the paper's "three-fold cross validation"); with ``--seeds N``, the mean over the seeds.
PSNR of an identical prediction is infinite; such a mean is reported as "inf".

Format "day2night-experiment-table/2" (docs/experiment.md, "table.json"): every row also
has its "kind" (untrained, trained, burst), its "scores" (mean, 95 % interval, scenes and
seeds per input and metric: stats.py), its "gain" over the untrained row and the paper's
numbers; the table its "label" (the preset), "protocol", "seeds", "compare_to",
"bootstrap", "comparisons" (paired differences against the reference row, with verdicts)
and "left_out" (rows the run dropped, and why)."""

import math
import pathlib

import numpy as np

from ..isos import NOISY_ISOS
from ..atomic import write_json, write_text
from . import stats
from . import tabletext as text
from .rows import UNTRAINED, select, tasks_of, test_keys, with_untrained
from .rows import units as row_units
from .runfolder import read_scores, unit_dir, unit_id
from .stats import bootstrap_seed
from ..variants import Isp, Noise

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
        "burst": (34.91, 0.8021, 31.39, 0.6526),  # the supplementary's burst denoising
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


def _value(v):
    return float(v)  # "inf"/"-inf"/"nan" strings too


def _load_units(config, out, task, row, splits):
    """The units of ``row`` per training seed: [(seed, [scores.json records])]; a burst
    row (no training) has one entry, seed None."""
    if row.source == "burst":
        path = pathlib.Path(out) / "units" / task / row.id / "all" / "scores.json"
        u = read_scores(out, path, task, row.id, "all", test_keys(task))
        u["seed"] = None
        return [(None, [u])]
    seeds = []
    for i, seed in enumerate(config.seed_list):
        units = []
        for fold, _ in row_units(row, splits):
            uid = unit_id(task, row.id, fold, None if i == 0 else seed)
            u = read_scores(out, unit_dir(out, uid) / "scores.json", task, row.id, fold,
                            test_keys(task), seed=None if i == 0 else seed)
            u["seed"] = seed
            units.append(u)
        seeds.append((seed, units))
    return seeds


def _per_scene(per_seed, key, metric, fold_of):
    """{scene: [value per seed]} of one input and metric (each scene's score from the model
    that did not see it)."""
    out = {}
    for _, units in per_seed:
        for u in units:
            for i in u["images"]:
                if i["input"] == str(key) and i["scene"] in fold_of:
                    out.setdefault(i["scene"], []).append(_value(i[metric]))
    return out


def _scene_weights(per_seed):
    """({scene: weight}, per_fold) of a row: its weighted mean over scenes is the row's
    (stats.py: a per-fold row's mean of fold means, a scene of fold k weighing n / (K n_k));
    None for a row tested on every scene by one model (equal weights)."""
    units = per_seed[0][1] if per_seed else []
    if all(u["fold"] == "all" for u in units):
        return None
    counts = {u["fold"]: len(u["test_scenes"]) for u in units}
    n, k = sum(counts.values()), len(counts)
    return {sc: n / (k * counts[u["fold"]]) for u in units for sc in u["test_scenes"]}


def _matrix(scenes_a, scenes_b=None):
    """(the common scenes, in order; a (seeds x scenes) array per side)."""
    common = sorted(set(scenes_a) & set(scenes_b if scenes_b is not None else scenes_a))
    mats = [np.array([d[sc] for sc in common], dtype=np.float64).T
            for d in ((scenes_a,) if scenes_b is None else (scenes_a, scenes_b))]
    return common, mats


def _interval(s):
    """The JSON of a stats summary: non-finite means as strings, the note kept."""
    out = {k: s[k] for k in ("mean", "ci_low", "ci_high", "n_scenes")}
    if "note" in s:
        out["note"] = s["note"]
    return out


class _Stats:
    """The bootstrap of one table (its seed, fold of each scene, and the rows' per-scene
    values per input and metric, with each row's scene weights)."""

    def __init__(self, config, splits):
        self.seed = bootstrap_seed(config.seed)
        self.fold_of = {sc: s["fold"] for s in splits for sc in s["test"]}
        self.values = {}  # (task, row) -> {(key, metric): {scene: [per seed]}}
        self.weights = {}  # (task, row) -> {scene: weight} of a per-fold row, else None

    def add(self, task, row_id, per_seed):
        self.values[(task, row_id)] = {
            (str(k), m): _per_scene(per_seed, k, m, self.fold_of)
            for k in test_keys(task) for m in METRICS}
        self.weights[(task, row_id)] = _scene_weights(per_seed)

    def _of(self, key, common):
        """(the scenes' weights or None, the scenes' folds when the row is per fold)."""
        w = self.weights[key]
        if w is None:
            return None, None
        return [w[sc] for sc in common], [self.fold_of[sc] for sc in common]

    def scores(self, task, row_id, seeds):
        out = {}
        for (k, m), d in self.values[(task, row_id)].items():
            common, (v,) = _matrix(d)
            w, folds = self._of((task, row_id), common)
            s = stats.summary(v, folds, w, self.seed)
            out.setdefault(k, {})[m] = {**_interval(s), "seeds": seeds,
                                        "seed_means": s["seed_means"],
                                        "seed_sd": s["seed_sd"]}
        return out

    def compare(self, task, row_id, ref_id):
        """{(input, metric): stats.compare's summary} of the row against ``ref_id``."""
        out = {}
        a, b = self.values[(task, row_id)], self.values[(task, ref_id)]
        for km in a:
            common, (va, vb) = _matrix(a[km], b[km])
            (wa, fa), (wb, fb) = self._of((task, row_id), common), self._of((task, ref_id),
                                                                               common)
            out[km] = stats.compare(va, vb, km[1], fa if fa is not None else fb, (wa, wb),
                                    self.seed)
        return out


def build(config, out, splits, n_scenes, n_days, left_out=()):
    """table.json of a run: ``config`` its resolved ExperimentConfig (tasks, rows, seeds,
    the record), ``out`` its folder (the units' scores.json), ``splits`` the fold manifest's,
    ``n_scenes`` and ``n_days`` the real scenes and day images it ran on, ``left_out``
    ({"task", "row", "why"}) rows the run dropped besides those this function finds."""
    st = _Stats(config, splits)
    rows_out, dropped = [], _left_out(config) + list(left_out)
    gone = {(g["task"], g["row"]) for g in dropped}
    ref = config.compare_to or UNTRAINED.id
    for task in tasks_of(config.task):
        for row in with_untrained(select(list(config.rows))):
            if (row.source == "burst" and task != "noisy") or (task, row.id) in gone:
                continue
            if row.source == "burst" and not _burst_done(out, task, row):
                dropped.append({"task": task, "row": row.id, "why": BURST_MISSING})
                continue
            per_seed = _load_units(config, out, task, row, splits)
            st.add(task, row.id, per_seed)
            rows_out.append(_row(config, task, row, per_seed, st))
    comparisons = []
    for r in rows_out:
        r["gain"] = None if r["row"] == UNTRAINED.id or (r["task"], UNTRAINED.id) not in \
            st.values else _gain(st, r)
        if r["row"] != ref and (r["task"], ref) in st.values:
            comparisons += _comparisons(st, r, ref)
    return {
        "format": "day2night-experiment-table/2",
        "config": config.record(),
        "label": config.label,
        "smoke": config.smoke,
        "not_the_paper": deviations(config, n_scenes, n_days),
        "protocol": {k: getattr(config, k) for k in PROTOCOL_KEYS},
        "seeds": config.seed_list,
        "compare_to": ref,
        "bootstrap": {"replicates": stats.REPLICATES, "level": stats.LEVEL, "seed": st.seed,
                      "method": stats.METHOD},
        "folds": splits,
        "rows": rows_out,
        "comparisons": comparisons,
        "left_out": dropped,
    }


PROTOCOL_KEYS = ("protocol", "targets", "noise", "synth_iso", "amp", "channels_last",
                 "folds_file")
BURST_MISSING = ("no burst scores (units/noisy/burst/all/scores.json): the real set holds one "
                 "frame per ISO, no burst to average")
FRESH_WHY = ("it synthesizes with day2night's ISP and noise (FreshPatches), and this run's "
             "targets or noise are the release's")


def _burst_done(out, task, row):
    return (pathlib.Path(out) / "units" / task / row.id / "all" / "scores.json").is_file()


def _left_out(config):
    """The rows the protocol dropped (protocol.fresh_rows), with the reason."""
    if "fresh" in config.rows or (config.targets == Isp.DAY2NIGHT
                                  and config.noise == Noise.DAY2NIGHT):
        return []
    return [{"task": t, "row": "fresh", "why": FRESH_WHY} for t in tasks_of(config.task)]


def _row(config, task, row, per_seed, st):
    """One row of table.json (without its gain)."""
    units = [u for _, us in per_seed for u in us]
    for u in units:
        u["mean"] = _unit_means(u, task)
    seed_means = [{str(k): {m: _mean(u["mean"][str(k)][m] for u in us) for m in METRICS}
                   for k in test_keys(task)} for _, us in per_seed]
    mean = {str(k): {m: _mean(sm[str(k)][m] for sm in seed_means) for m in METRICS}
            for k in test_keys(task)}
    seeds = [] if row.source == "burst" else list(config.seed_list)
    kind = row.source if row.source in ("untrained", "burst") else "trained"
    return {"task": task, "row": row.id, "label": row.label, "kind": kind, "units": units,
            "mean": mean, "scores": st.scores(task, row.id, seeds),
            "paper": paper_of(task, row.id)}


def _gain(st, r):
    """The row's paired difference over the untrained row, per input and metric."""
    out = {}
    for (k, m), s in st.compare(r["task"], r["row"], UNTRAINED.id).items():
        out.setdefault(k, {})[m] = _interval(s)
    return out


def _comparisons(st, r, ref):
    return [{"task": r["task"], "row": r["row"], "reference": ref, "input": k, "metric": m,
             **_interval(s), "seeds": r["scores"][k][m]["seeds"], "verdict": s["verdict"]}
            for (k, m), s in st.compare(r["task"], r["row"], ref).items()]


def paper_of(task, row_id):
    """The paper's numbers of a row (table.json's "paper"), or None."""
    p = PAPER[task].get(row_id)
    if p is None:
        return None
    if task == "clean":
        return {"clean": dict(zip(METRICS, p))}
    lo, hi = NOISY_ISOS
    return {str(lo): {"psnr": p[0], "ssim": p[1]}, str(hi): {"psnr": p[2], "ssim": p[3]}}


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


BANNERS = {
    "smoke": "**Smoke run** (below the mini preset: network width {width}, {epochs} epochs; "
             "the paper's UNet: width 32, 500 epochs). These are not the paper's numbers.",
    "mini": "**Mini preset** (network width 8, 32 x 32 patches, batches of 8, lr 1e-2, 40 "
            "epochs: the night ISP learning on a CPU). These are not the paper's numbers.",
    "custom": "**Custom settings** (network width {width}, {epochs} epochs, {patch} x {patch} "
              "patches, batches of {batch}, lr {lr:g}). These are not the paper's numbers.",
}


def _header(t):
    """The lines above the tables: label, deviations, options, protocol, seeds, method."""
    cfg, p = t["config"], t["protocol"]
    values = {"width": cfg["width"], "epochs": cfg["epochs"], "patch": cfg.get("patch", 64),
              "batch": cfg.get("batch", 128), "lr": cfg.get("lr", 1e-3)}
    lines = ["# day2night experiment: Tables 1 and 2", ""]
    if t["label"] in BANNERS:
        lines += [BANNERS[t["label"]].format(**values), ""]
    if t["not_the_paper"]:
        lines += ["Differs from the paper's protocol: " + "; ".join(t["not_the_paper"]) + ".", ""]
    seeds = t["seeds"]
    b = t["bootstrap"]
    lines += [
        f"Options: task {cfg['task']}, epochs {cfg['epochs']}, seed {cfg['seed']}, "
        f"folds {cfg['folds']}, width {cfg['width']}, device {cfg['device']}.",
        f"Protocol: {text.protocol_sentence(p)}",
        f"Training seeds: {', '.join(map(str, seeds))} ({len(seeds)} per unit; folds and "
        f"synthetic data of seed {seeds[0]}).",
        "Rows trained on synthesis only are tested on every real scene; rows with real data "
        "are the mean over the folds of each fold's test scenes.",
        f"Each cell: the mean [95 % interval] over the test scenes (n below)"
        f"{' and the seeds' if len(seeds) > 1 else ''}, by a {b['replicates']}-replicate "
        f"bootstrap (each scene's score from the model that did not see it, scenes "
        f"resampled across the test set{', seeds resampled' if len(seeds) > 1 else ''}; "
        f"bootstrap seed {b['seed']}), widened to the Student-t interval of its standard "
        "error where that is wider. The gain over untrained and the comparisons are paired "
        f"per-scene differences, bootstrapped the same way. Fewer than {stats.MIN_SCENES} "
        f"test scenes, or a per-fold row with a fold of fewer than {stats.MIN_PER_FOLD}: "
        f"{stats.TOO_FEW}, and no verdict.",
        "",
    ]
    return lines


def _md_cell(r, k, m):
    """A score cell: ``mean [95 % interval]``, and the spread over seeds when it has one."""
    s = r["scores"][k][m]
    sd = text.num(s.get("seed_sd"))
    return text.cell(s, text.DIGITS[m]) + \
        ("" if sd is None else f", sd over seeds {text.fmt(sd, text.DIGITS[m])}")


def _table(rows, task, title):
    """One task's table, the columns of the page's (tabletext.columns): scenes / seeds, each
    (input, metric) with its interval, the gains over the untrained row in the same order,
    and the paper's numbers."""
    cols = text.columns(task)
    first = rows[0]["scores"][cols[0][0]][cols[0][1]] if rows else {}
    multi = len(text.inputs_of(task)) > 1
    heads = [f"{'ISO ' + k + ' ' if multi else ''}{text.NAMES[m]}" for k, m in cols]
    paper = [(k, m) for k, m in cols if m in text.PAPER_METRICS[task]]
    paper_head = " / ".join(f"{'ISO ' + k + ' ' if multi else ''}{text.NAMES[m]}"
                            for k, m in paper)
    lines = [f"## {title}, {first.get('n_scenes', 0)} test scenes", "",
             "| model | scenes / seeds | " + " | ".join(heads)
             + f" | gain over untrained ({' / '.join(heads)}) | paper ({paper_head}) |",
             "|---" * (len(heads) + 4) + "|"]
    for r in rows:
        s0 = r["scores"][cols[0][0]][cols[0][1]]
        n = f"{s0.get('n_scenes', '-')} / {text.seeds_count(s0.get('seeds'))}"
        cells = [_md_cell(r, k, m) for k, m in cols]
        gain = " / ".join(text.cell(r["gain"][k][m], text.DIGITS[m], sign=True)
                          for k, m in cols) if r["gain"] else "-"
        p = r["paper"]
        ps = " / ".join(text.fmt(p[k][m], text.DIGITS[m]) for k, m in paper) if p else "-"
        lines.append(f"| {r['label']} | {n} | " + " | ".join(cells) + f" | {gain} | {ps} |")
    return lines + [""]


def _comparison_lines(t, task, labels):
    comps = [c for c in t["comparisons"] if c["task"] == task]
    if not comps:
        return []
    ref = labels.get((task, t["compare_to"]), t["compare_to"])
    lines = [f"### Comparisons against {ref} ({task} task)", "",
             "Paired per-scene difference row - reference (PSNR, SSIM: positive is better; "
             "Delta E: negative is better), its 95 % interval and the verdict at 95 %.", "",
             "| model | input | metric | mean difference | 95 % interval | scenes | seeds "
             "| verdict |",
             "|---|---|---|---|---|---|---|---|"]
    for c in comps:
        d = text.DIGITS[c["metric"]]
        lines.append(f"| {labels.get((task, c['row']), c['row'])} | "
                     f"{text.input_name(c['input'])} | {text.NAMES[c['metric']]} | "
                     f"{text.fmt(c['mean'], d, sign=True)} | {text.bounds(c, d, sign=True)} | "
                     f"{c.get('n_scenes', '-')} | {text.seeds_count(c.get('seeds'))} | "
                     f"{c['verdict'] or 'no verdict'} |")
    return lines + [""]


def markdown(t):
    lines = _header(t)
    by_task = {}
    for r in t["rows"]:
        by_task.setdefault(r["task"], []).append(r)
    labels = {(r["task"], r["row"]): r["label"] for r in t["rows"]}
    lo, hi = (str(i) for i in NOISY_ISOS)
    if "clean" in by_task:
        lines += _table(by_task["clean"], "clean", "Table 1: clean (ISO 50 merged raw input)")
    if "noisy" in by_task:
        lines += _table(by_task["noisy"], "noisy",
                        f"Table 2: noisy (first frame at ISO {lo} and {hi})")
    if t["comparisons"]:
        lines += ["## Comparisons", ""]
        lines += _comparison_lines(t, "clean", labels)
        lines += _comparison_lines(t, "noisy", labels)
    if t["left_out"]:
        lines += ["Left out: " + "; ".join(f"{x['row']} ({x['task']} task): {x['why']}"
                                             for x in t["left_out"]) + ".", ""]
    lines.append("Per row, fold, seed and image: table.json. Test scenes: index.html.")
    return "\n".join(lines) + "\n"


def write(out, t, md=None):
    """RUN/table.json and RUN/table.md of the table ``t`` (:func:`build`'s; ``md``: its
    :func:`markdown`, when already made)."""
    md = markdown(t) if md is None else md
    write_json(pathlib.Path(out) / "table.json", t)
    write_text(pathlib.Path(out) / "table.md", md)
