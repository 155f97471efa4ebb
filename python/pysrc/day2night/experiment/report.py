"""RUN/index.html, the run's report: what was run (preset label, options, protocol, how it
differs from the paper, rows left out), Tables 1 and 2 as HTML tables with confidence
intervals, gains and the paper's numbers (report_tables.py), the comparisons against the
reference row, the learning curves per row (curves.py; also RUN/curves_<task>.svg), and the
shown test scenes of every row with every test scene's scores (report_grid.py). Also writes
the curves as TensorBoard event files under RUN/tb (tb.py).

Every text from table.json goes through html.escape; the page refers to nothing outside the
run folder."""

import html
import pathlib
import re

from ..atomic import write_text
from . import curves, demap, report_grid, report_tables, tb
from . import tabletext as text
from .prepare import log

e = html.escape
STYLE = """body{font-family:sans-serif;margin:1em;max-width:1500px}
table{border-collapse:collapse;margin:0.5em 0}
th,td{border:1px solid #ccc;padding:3px 6px;font-size:13px;vertical-align:top}
table.scores td{text-align:right;white-space:nowrap}
table.scores tbody th{text-align:left;min-width:11em}
.ci{color:#555;font-size:11px}.gain{color:#246;font-size:11px}
td.paper,th.paper{background:#f4f1e8;color:#444}
td.best,span.best{background:#d9f2d9;font-weight:bold}
tr.untrained,tr.burst{color:#777;font-style:italic;background:#fafafa}
td.better{background:#cdeccd}td.worse{background:#f6cccc}td.same{background:#eee}
table.grid td{padding:1px}table.grid th{font-weight:normal;text-align:left}
td.missing{width:192px;font-size:11px;color:#a00}
.key,.note{font-size:12px;color:#333;max-width:1100px}
dl.run{display:grid;grid-template-columns:max-content auto;gap:2px 12px;font-size:13px}
dl.run dt{font-weight:bold}dl.run dd{margin:0}
nav.toc{font-size:13px;border:1px solid #ccc;background:#fafafa;padding:4px 12px;
display:inline-block}nav.toc ul{margin:2px 0;padding-left:1.4em}
svg.scale text{font-family:sans-serif;fill:#333}"""
LABELS = {"paper": "the paper's settings (--preset paper)",
          "mini": "the mini preset (--preset mini: learns on a CPU; not the paper's numbers)",
          "smoke": "a smoke run (settings below both presets: not the paper's numbers)",
          "custom": "custom settings (a preset with flags that override it)"}


def scenes_to_show(splits, n):
    """(scenes, why) for ``--show n``: up to ``n`` scenes taken in turn from the folds' test
    lists (fold 0's first, fold 1's first, ..., then the second of each), so every row, the
    synthetic ones (tested on every scene) and the per-fold ones (each scene in one fold's
    test list), has a prediction for each; ``why`` says why there are fewer than ``n``."""
    lists = [list(s.get("test") or []) for s in splits]
    order = [lst[i] for i in range(max(map(len, lists), default=0)) for lst in lists
             if i < len(lst)]
    scenes = order[:n]
    why = None
    if len(scenes) < n:
        why = (f"--show {n}: showing {len(scenes)} test scene(s), all the real set has "
               "(every scene is in one fold's test list)")
    return scenes, why


def _value(v):
    if v is None:
        return "-"
    return " ".join(map(str, v)) if isinstance(v, (list, tuple)) else str(v)


def _pairs(items):
    """``key value, key value, ...`` of a dict's items, sorted ("-" for none)."""
    return ", ".join(f"{k} {_value(v)}" for k, v in sorted(items)) or "-"


def _dl(items):
    body = "".join(f"<dt>{e(str(k))}</dt><dd>{e(str(v))}</dd>" for k, v in items)
    return f'<dl class="run">{body}</dl>'


def run_section(t):
    """What was run: the label, options, protocol, seeds, bootstrap and the deviations."""
    cfg = t.get("config") or {}
    label = t.get("label")
    what = LABELS.get(label, "-" if label is None else label)
    if label is None and t.get("smoke"):
        what = "- (a network narrower than the paper's: not the paper's numbers)"
    items = [("run", what), ("protocol", text.protocol_sentence(t.get("protocol")))]
    seeds = t.get("seeds")
    items.append(("training seeds", "-" if not seeds else ", ".join(map(str, seeds))))
    b = t.get("bootstrap") or {}
    items.append(("confidence intervals", "-" if not b else
                  f"{round(100 * float(b.get('level', 0.95)))} % bootstrap, "
                  f"{b.get('replicates', '-')} replicates, seed {b.get('seed', '-')}: "
                  f"{b.get('method', '-')}"))
    items.append(("reference row of the comparisons", t.get("compare_to") or "-"))
    items.append(("options (config.json)", _pairs(cfg.items())))
    dev = t.get("not_the_paper") or []
    parts = ['<h2 id="run">The run</h2>', _dl(items)]
    parts.append("<p><b>Differs from the paper's protocol:</b> "
                 + (e("; ".join(dev)) if dev else "nothing listed") + ".</p>")
    return parts + left_out(t)


def left_out(t):
    """The rows not in the tables and why (table.json "left_out")."""
    rows = t.get("left_out") or []
    if not rows:
        return []
    items = "".join(f"<li>{e(str(r.get('task', '-')))} task, row "
                    f"{e(str(r.get('row', '-')))}: {e(str(r.get('why', '-')))}</li>"
                    for r in rows)
    return ["<p><b>Rows left out:</b></p>", f"<ul>{items}</ul>"]


def _curves(files, t, tasks):
    """The learning curves of each task (curves.py), inline and as RUN/curves_<task>.svg
    (added to ``files``, {name: text})."""
    parts = ['<h2 id="curves">Learning curves</h2>',
             '<p class="note">Per row, every unit (fold, seed) in its own colour: the training '
             "loss (solid) and the validation L1 (dashed) per epoch, epoch 0 the untrained "
             "network; one logarithmic scale per task. Synthetic rows validate on the "
             "synthetic validation images, per-fold rows on their fold's real validation "
             "scenes. TensorBoard: <code>tensorboard --logdir tb</code> in the run folder."
             "</p>"]
    drawn = False
    for task in tasks:
        chart = curves.svg(t, task)
        if chart is not None:
            files[f"curves_{task}.svg"] = chart
            parts += [f'<h3 id="curves-{e(task)}">{e(task)} task</h3>', chart]
            drawn = True
    return parts if drawn else parts[:1] + ["<p>No unit has a training history.</p>"]


def _scenes_head(scenes, why):
    parts = ['<h2 id="scenes">Test scenes</h2>',
             '<p class="note">Per row: the network input, the prediction, the target and the '
             "per-pixel Delta E 2000 of prediction and target (display sRGB, in the colour "
             "scale below) of the shown scenes, then every test scene's scores. Shown: "
             f"{e(', '.join(scenes)) if scenes else 'none (--show 0)'}.</p>", demap.legend()]
    if why:
        parts.append(f'<p class="note">{e(why)}</p>')
    return parts


HEADING = re.compile(r'<h([23]) id="([^"]+)">(.*?)</h\1>', re.S)


def toc(parts):
    """The table of contents of the page's ``parts``: a link to every <h2> and <h3> that has
    an id, nested (found in the HTML itself, so a link never points at a missing id)."""
    items, open_sub = [], False
    for level, ident, title in HEADING.findall("\n".join(parts)):
        label = re.sub(r"<[^>]*>", "", title)  # already escaped text
        if level == "3" and not open_sub and items:
            items[-1] = items[-1].removesuffix("</li>") + "<ul>"
            open_sub = True
        elif level == "2" and open_sub:
            items.append("</ul></li>")
            open_sub = False
        items.append(f'<li><a href="#{ident}">{label}</a></li>')
    if open_sub:
        items.append("</ul></li>")
    if not items:
        return []
    return ['<nav class="toc" aria-label="Contents"><b>Contents</b><ul>', *items,
            "</ul></nav>"]


def write(out, t, tasks, report_scenes, show=None):
    """RUN/index.html (and RUN/curves_<task>.svg, RUN/tb) of the table ``t`` (table.build's)
    of a run of ``tasks``, showing the test scenes ``report_scenes`` (:func:`scenes_to_show`
    of ``--show`` ``show``)."""
    write_built(out, t, build(out, t, tasks, report_scenes, show))


def write_built(out, t, files):
    """The files :func:`build` made ({name: text}), then RUN/tb."""
    for name, text in files.items():
        write_text(pathlib.Path(out) / name, text)
    written = tb.write(out, t)
    if isinstance(written, str):
        log(written)


def build(out, t, tasks, report_scenes, show=None):
    """{name: text} of RUN/index.html and RUN/curves_<task>.svg (:func:`write`), built in
    memory (nothing written: a report is built whole before any of it is written)."""
    out = pathlib.Path(out)
    files = {}
    why = None
    if show is not None and len(report_scenes) < show:
        why = scenes_to_show(t.get("folds") or [], show)[1]
    parts = ["<!doctype html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>day2night experiment</title>", f"<style>{STYLE}</style></head><body>",
             "<h1>day2night experiment: Tables 1 and 2</h1>"]
    parts += run_section(t)
    for task in tasks:
        parts += report_tables.task_table(t, task)
    parts += report_tables.comparisons(t)
    parts += _curves(files, t, tasks)
    parts += _scenes_head(report_scenes, why)
    parts += report_grid.section(out, t, report_scenes)
    parts.append("</body></html>")
    parts[5:5] = toc(parts)
    return {"index.html": "\n".join(parts) + "\n", **files}
