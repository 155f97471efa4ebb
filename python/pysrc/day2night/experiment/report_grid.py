"""The test scenes of RUN/index.html (report.py): per row, a grid of the shown scenes (input,
prediction, target, Delta E 2000 map, under column headers, with the scene's scores) and a
table of its scores on every test scene.

The PNGs are RUN/img/<task>/scenes/<scene>_<input>_{input,target}.png (once per task) and
RUN/img/<task>/<row>/<scene>_<input>_{pred,de}.png (unit.score_unit writes them for the shown
scenes). A prediction missing on disk (a unit scored by an earlier run that showed other
scenes) is said in its cell, not shown as a broken image."""

import html
import pathlib
import re
import urllib.parse

from .names import image_stem
from .tabletext import DIGITS, fmt, inputs_of

e = html.escape
COLUMNS = ("input", "prediction", "target", "Delta E 2000")


def scores_of(unit, sid, key):
    """The per-scene record {"scene", "input", "psnr", "ssim", "delta_e"} or None."""
    for i in unit.get("images") or []:
        if i.get("scene") == sid and str(i.get("input")) == str(key):
            return i
    return None


def unit_of(r, sid):
    """The unit of row ``r`` that tested scene ``sid`` (the first seed's), or None."""
    return next((u for u in r.get("units", []) if sid in (u.get("test_scenes") or [])), None)


def url(path):
    """A relative path as an attribute's URL: each segment percent-encoded (a scene named
    ``a#b?c%zz`` is a file name, not a fragment or a query), then HTML-escaped by the
    caller."""
    return "/".join(urllib.parse.quote(seg, safe="") for seg in path.split("/"))


def anchor(*parts):
    """An id for a heading of the page: ``parts`` joined by "-", every character outside
    [A-Za-z0-9_.-] replaced by "_" (so a link to it needs no encoding)."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", "-".join(map(str, parts)))


def _img(out, src, alt):
    if not (out / src).is_file():
        return (f'<td class="missing">{e(alt)}: no image (not written when this unit was '
                "scored: a unit of an earlier run that showed other scenes)</td>")
    return (f'<td><img src="{e(url(src))}" alt="{e(alt)}" width="192" loading="lazy"></td>')


def _scores_text(s):
    if s is None:
        return "no score"
    return (f"PSNR {fmt(s.get('psnr'), DIGITS['psnr'])} dB<br>"
            f"SSIM {fmt(s.get('ssim'), DIGITS['ssim'])}<br>"
            f"Delta E {fmt(s.get('delta_e'), DIGITS['delta_e'])}")


def _grid_row(out, r, unit, sid, key):
    task, row = r["task"], r["row"]
    stem = image_stem(sid, key)
    where = "" if unit.get("fold") in (None, "all") else f"<br>fold {e(str(unit['fold']))}"
    inp = "merged raw" if key == "clean" else f"ISO {key}"
    return ("<tr>"
            f'<th scope="row">{e(sid)}<br>{e(inp)}{where}<br>'
            f"{_scores_text(scores_of(unit, sid, key))}</th>"
            + _img(out, f"img/{task}/scenes/{stem}_input.png", f"{sid} input")
            + _img(out, f"img/{task}/{row}/{stem}_pred.png", f"{sid} prediction")
            + _img(out, f"img/{task}/scenes/{stem}_target.png", f"{sid} target")
            + _img(out, f"img/{task}/{row}/{stem}_de.png", f"{sid} Delta E 2000")
            + "</tr>")


def grid(out, r, scenes):
    """The image grid of row ``r`` over ``scenes`` ([] when none of them was tested by it)."""
    body = []
    for sid in scenes:
        unit = unit_of(r, sid)
        if unit is None:
            continue
        body += [_grid_row(out, r, unit, sid, key) for key in inputs_of(r["task"])]
    if not body:
        return []
    head = "".join(f'<th scope="col">{e(c)}</th>' for c in ("scene, input, scores", *COLUMNS))
    return ['<table class="grid"><thead><tr>', head, "</tr></thead><tbody>", *body,
            "</tbody></table>"]


def score_table(r):
    """Every test scene's scores of row ``r`` (per unit: fold, seed), in a <details>."""
    lines = []
    for u in r.get("units", []):
        fold = "" if u.get("fold") in (None, "all") else str(u["fold"])
        seed = "" if u.get("seed") is None else str(u["seed"])
        for i in u.get("images") or []:
            cols = [i.get("scene"), i.get("input"), fold, seed,
                    *(fmt(i.get(m), DIGITS[m]) for m in ("psnr", "ssim", "delta_e"))]
            lines.append("<tr>" + "".join(f"<td>{e(str(c))}</td>" for c in cols) + "</tr>")
    if not lines:
        return []
    return [f"<details><summary>Scores of every test scene ({len(lines)} test inputs)"
            "</summary>",
            '<table class="per-scene"><thead><tr><th>scene</th><th>input</th><th>fold</th>'
            "<th>seed</th><th>PSNR</th><th>SSIM</th><th>Delta E</th></tr></thead><tbody>",
            *lines, "</tbody></table></details>"]


def section(out, t, scenes):
    """The test-scene section of every row of table ``t``, showing ``scenes``."""
    out = pathlib.Path(out)
    parts = []
    for r in t.get("rows", []):
        label = r.get("label") or r["row"]
        parts.append(f'<h3 id="{anchor("scenes", r["task"], r["row"])}">{e(label)} '
                     f"({e(r['task'])} task)</h3>")
        parts += grid(out, r, scenes)
        parts += score_table(r)
    return parts
