"""RUN/index.html: the table, the validation L1 per epoch of every row (inline SVG, also
RUN/val_l1_<task>.svg) and a few test scenes per row (input, prediction, target, Delta E 2000
map, as PNGs under RUN/img/)."""

import html
import pathlib

from ..isos import NOISY_ISOS
from . import curves
from ..atomic import write_text
from .table import markdown


def _img(src, caption):
    return (
        f'<figure><img src="{html.escape(src)}" width="192" loading="lazy">'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _scores(unit, sid, key):
    for i in unit["images"]:
        if i["scene"] == sid and i["input"] == str(key):
            return i
    return None


def _curves(out, t, tasks):
    """Validation L1 per epoch of each row (curves.py), inline and as RUN/val_l1_<task>.svg."""
    parts = []
    for task in tasks:
        chart = curves.svg(t, task)
        if chart is not None:
            write_text(out / f"val_l1_{task}.svg", chart)
            parts += [f"<h2>Validation L1 per epoch ({html.escape(task)} task)</h2>",
                      chart]
    return parts


def write(out, t, tasks, report_scenes):
    """RUN/index.html of the table ``t`` (table.build's) of a run of ``tasks``, showing the
    test scenes ``report_scenes``."""
    out = pathlib.Path(out)
    parts = [
        "<!doctype html><meta charset=utf-8><title>day2night experiment</title>",
        "<style>body{font-family:sans-serif;margin:1em}figure{display:inline-block;margin:2px}"
        "figcaption{font-size:11px}pre{background:#f4f4f4;padding:8px}</style>",
        "<h1>day2night experiment: Tables 1 and 2</h1>",
        f"<pre>{html.escape(markdown(t))}</pre>",
        "<p>Delta E maps: CIEDE2000 per pixel, black 0, white 10 or more.</p>",
    ]
    parts += _curves(out, t, tasks)
    for r in t["rows"]:
        task, row = r["task"], r["row"]
        parts.append(f"<h2>{html.escape(r['label'])} ({task} task)</h2>")
        keys = ["clean"] if task == "clean" else list(NOISY_ISOS)
        for sid in report_scenes:
            unit = next((u for u in r["units"] if sid in u.get("test_scenes", [])), None)
            if unit is None:
                continue
            for key in keys:
                parts += _scene(task, row, unit, sid, key)
    write_text(out / "index.html", "\n".join(parts) + "\n")


def _scene(task, row, unit, sid, key):
    """The figures of one test input of a row: input, prediction, target, Delta E map."""
    s = _scores(unit, sid, key)
    stem = f"{sid}_{key}"
    sc = "" if s is None else (
        f" PSNR {s['psnr'] if isinstance(s['psnr'], str) else round(s['psnr'], 2)}"
        f", SSIM {s['ssim'] if isinstance(s['ssim'], str) else round(s['ssim'], 4)}"
        f", Delta E {round(float(s['delta_e']), 3)}")
    return ["<div>",
            _img(f"img/{task}/scenes/{stem}_input.png", f"{sid} input ({key})"),
            _img(f"img/{task}/{row}/{stem}_pred.png", f"prediction, fold {unit['fold']}:{sc}"),
            _img(f"img/{task}/scenes/{stem}_target.png", "target"),
            _img(f"img/{task}/{row}/{stem}_de.png", "Delta E 2000"),
            "</div>"]
