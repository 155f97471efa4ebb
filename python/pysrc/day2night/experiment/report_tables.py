"""The HTML tables of RUN/index.html (report.py): Tables 1 and 2 with each row's mean, its
95 % confidence interval, the gain over the untrained network and the paper's numbers beside
them, the best trained value per column marked; the comparisons against the reference row.

Read from table.json (docs/experiment.md, "table.json"): a table of format /1, without the
confidence intervals, gains, paper numbers or comparisons, renders with "-" in their place."""

import html

from . import tabletext as text
from .tabletext import METRICS, PAPER_METRICS, fmt, inputs_of, num

#: Rows that are references, not candidates: never marked best.
REFERENCE_KINDS = ("untrained", "burst")
VERDICT_CLASS = {"better": "better", "worse": "worse", "not distinguishable": "same"}
TITLES = {"clean": "Table 1: clean task (ISO 50 merged raw input)",
          "noisy": "Table 2: noisy task (first frame at ISO {} and {})".format(
              *inputs_of("noisy"))}

e = html.escape


def kind(r):
    """A row's kind (format /1 tables have none: told from its id)."""
    if r.get("kind"):
        return r["kind"]
    return r["row"] if r["row"] in REFERENCE_KINDS else "trained"


def cell(r, key, metric):
    """{"mean", "ci_low", ...} of one row, input and metric (format /1: the mean only)."""
    s = ((r.get("scores") or {}).get(key) or {}).get(metric)
    if isinstance(s, dict):
        return s
    return {"mean": ((r.get("mean") or {}).get(key) or {}).get(metric)}


def best(rows, key, metric, direction):
    """The best mean of the trained rows in one column (None without a finite one)."""
    vals = [num(cell(r, key, metric).get("mean")) for r in rows
            if kind(r) not in REFERENCE_KINDS]
    vals = [v for v in vals if v is not None and v == v]
    if not vals:
        return None
    return max(vals) if direction > 0 else min(vals)


def _run_cell(r, key, metric, digits, top):
    c = cell(r, key, metric)
    mean = num(c.get("mean"))
    cls = ' class="best"' if top is not None and mean is not None and mean == top else ""
    lines = [f"<b>{e(fmt(mean, digits))}</b>"]
    if "ci_low" in c:
        lines.append(f'<span class="ci">{e(text.bounds(c, digits))}</span>')
    if num(c.get("seed_sd")) is not None:
        lines.append(f'<span class="ci">sd over seeds {e(fmt(c["seed_sd"], digits))}</span>')
    g = ((r.get("gain") or {}).get(key) or {}).get(metric)
    if isinstance(g, dict):
        lines.append(f'<span class="gain">gain {e(fmt(g.get("mean"), digits, sign=True))}'
                     f'<br>{e(text.bounds(g, digits, sign=True))}</span>')
    return f"<td{cls}>" + "<br>".join(lines) + "</td>"


def _paper_cell(r, key, metric, digits):
    p = ((r.get("paper") or {}).get(key) or {}).get(metric)
    return f'<td class="paper">{e(fmt(p, digits))}</td>'


def _n_cell(r, key):
    c = cell(r, key, "psnr")
    n = c.get("n_scenes")
    seeds = c.get("seeds")
    if n is None and seeds is None:
        return "<td>-</td>"
    s = text.seeds_count(seeds)
    title = "" if not seeds else f' title="seeds {e(", ".join(map(str, seeds)))}"'
    return f"<td{title}>{e(str('-' if n is None else n))} / {e(s)}</td>"


def _head(task, keys):
    top = ['<tr><th rowspan="2">model</th><th rowspan="2">scenes / seeds</th>']
    sub = ["<tr>"]
    for key in keys:
        name = text.input_name(key)
        top.append(f'<th colspan="{len(METRICS) + len(PAPER_METRICS[task])}">{e(name)}</th>')
        for metric, label, _, direction in METRICS:
            arrow = "higher is better" if direction > 0 else "lower is better"
            sub.append(f'<th title="{arrow}">{e(label)} {"&uarr;" if direction > 0 else "&darr;"}'
                       "</th>")
            if metric in PAPER_METRICS[task]:
                sub.append('<th class="paper">paper</th>')
    return "".join(top) + "</tr>", "".join(sub) + "</tr>"


def _row(r, keys, tops):
    parts = [f'<tr class="{e(kind(r))}"><th scope="row">{e(r.get("label") or r["row"])}</th>',
             _n_cell(r, keys[0])]
    for key in keys:
        for metric, _, digits, _ in METRICS:
            parts.append(_run_cell(r, key, metric, digits, tops[(key, metric)]))
            if metric in PAPER_METRICS[r["task"]]:
                parts.append(_paper_cell(r, key, metric, digits))
    return "".join(parts) + "</tr>"


def task_table(t, task):
    """The HTML of one task's table (its heading, the table and its key), or [] when the
    run has no row of ``task``."""
    rows = [r for r in t.get("rows", []) if r.get("task") == task]
    if not rows:
        return []
    keys = inputs_of(task)
    tops = {(k, m): best(rows, k, m, d) for k in keys for m, _, _, d in METRICS}
    head, sub = _head(task, keys)
    body = [_row(r, keys, tops) for r in rows]
    return [f"<h2 id=\"table-{e(task)}\">{e(TITLES[task])}</h2>",
            f'<table class="scores"><thead>{head}{sub}</thead><tbody>',
            *body, "</tbody></table>",
            '<p class="key">Each cell: the mean over the test scenes (per-fold rows: the mean '
            "of the folds' means); below it the 95 % bootstrap interval, the spread over "
            "seeds (with several), and the gain over the untrained network with its interval. "
            '<span class="best">Highlighted</span>: the best trained row per column (PSNR and '
            "SSIM highest, Delta E lowest); the untrained and burst rows are references "
            "(in grey) and not ranked. \"paper\": the paper's number of that row.</p>"]


def comparisons(t):
    """The comparisons section: each row against the reference row (table.json
    "comparisons"), or a line saying the table has none."""
    comps = t.get("comparisons")
    ref = t.get("compare_to") or "-"
    head = [f"<h2 id=\"comparisons\">Comparisons against the reference row ({e(ref)})</h2>"]
    if not comps:
        return head + ["<p>This table has no comparisons (written by an earlier version: "
                       "rerun the table to get them).</p>"]
    labels = {(r.get("task"), r.get("row")): r.get("label") or r.get("row")
              for r in t.get("rows", [])}
    rows = [_comparison_row(c, labels) for c in comps]
    return head + [
        "<p>Paired per-scene difference row minus reference over the same test scenes: its "
        "mean and 95 % bootstrap interval. PSNR and SSIM: positive is better; Delta E: "
        "negative is better. The verdict is better or worse when the interval excludes 0, "
        "else not distinguishable. Scenes: the test scenes paired; seeds: how many training "
        "seeds.</p>",
        '<table class="comparisons"><thead><tr><th>task</th><th>model</th><th>reference</th>'
        "<th>input</th><th>metric</th><th>mean difference</th><th>95 % interval</th>"
        "<th>scenes</th><th>seeds</th><th>verdict</th></tr></thead><tbody>",
        *rows, "</tbody></table>"]


def _comparison_row(c, labels):
    metric = c.get("metric")
    digits = text.DIGITS.get(metric, 4)
    label = text.NAMES.get(metric, metric or "-")
    verdict = c.get("verdict") or "-"
    task = c.get("task")
    seeds = c.get("seeds")
    cols = [task, labels.get((task, c.get("row")), c.get("row")),
            labels.get((task, c.get("reference")), c.get("reference")),
            None if c.get("input") is None else text.input_name(str(c["input"])), label,
            fmt(c.get("mean"), digits, sign=True), text.bounds(c, digits, sign=True),
            c.get("n_scenes")]
    tds = "".join(f"<td>{e(str('-' if v is None else v))}</td>" for v in cols)
    title = "" if not seeds else f' title="seeds {e(", ".join(map(str, seeds)))}"'
    tds += f"<td{title}>{e(text.seeds_count(seeds))}</td>"
    cls = VERDICT_CLASS.get(verdict, "same")
    return f'<tr>{tds}<td class="verdict {cls}">{e(verdict)}</td></tr>'
