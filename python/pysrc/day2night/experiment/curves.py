"""Learning curves as small multiples: one small SVG chart per row of a task, each with the
training loss (solid) and the validation L1 (dashed) per epoch of every unit of the row (one
colour per fold and seed, named in the chart's legend), on one logarithmic scale per task so
the charts compare. index.html shows them under the tables; RUN/curves_<task>.svg holds the
same charts side by side.

The numbers are the trainer's: ``history[i]["loss"]`` (the mean training L1 of epoch i) and
``history[i]["val_loss"]`` (the mean L1 over the validation patches after epoch i), drawn at
epoch i + 1; ``initial["val_loss"]`` (the untrained weights') at epoch 0."""

import colorsys
import html
import math

COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")
#: One chart: width, height, plot margins (left, right, top, bottom).
W, H, PAD_L, PAD_R, PAD_T, PAD_B = 300, 210, 46, 8, 30, 64
COLUMNS = 3


def colours(n):
    """``n`` distinct colours: the ten of the palette, or evenly spaced hues beyond ten."""
    if n <= len(COLOURS):
        return list(COLOURS[:n])
    out = []
    for i in range(n):
        r, g, b = colorsys.hsv_to_rgb(i / n, 0.75, 0.8)
        out.append(f"#{round(r * 255):02x}{round(g * 255):02x}{round(b * 255):02x}")
    return out


def finite(v):
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def unit_name(u):
    """A unit's name in a legend: its fold and seed ("all": the one synthetic unit)."""
    parts = []
    if u.get("fold") not in (None, "all"):
        parts.append(f"fold {u['fold']}")
    if u.get("seed") is not None:
        parts.append(f"seed {u['seed']}")
    return ", ".join(parts) or "one unit"


def unit_lines(u):
    """(train loss points, validation L1 points) of one unit: [(epoch, value), ...]."""
    train = [(int(h["epoch"]) + 1, float(h["loss"])) for h in u.get("history") or []
             if finite(h.get("loss"))]
    val = []
    init = (u.get("initial") or {}).get("val_loss")
    if finite(init):
        val.append((0, float(init)))
    val += [(int(h["epoch"]) + 1, float(h["val_loss"])) for h in u.get("history") or []
            if finite(h.get("val_loss"))]
    return train, val


def series(t, task):
    """[(row label, [(unit name, train points, val points), ...]), ...]: the rows of
    ``task`` with a history, in the table's order."""
    out = []
    for r in t.get("rows", []):
        if r.get("task") != task:
            continue
        units = [(unit_name(u), *unit_lines(u)) for u in r.get("units", [])]
        units = [x for x in units if x[1] or x[2]]
        if units:
            out.append((r.get("label") or r["row"], units))
    return out


class Scale:
    """Epoch -> x and value -> y of one chart (y logarithmic when every value is positive)."""

    def __init__(self, x1, lo, hi):
        self.x1 = max(x1, 1)
        self.log = lo > 0
        f = math.log10 if self.log else float
        self.y0, self.y1 = f(lo), f(hi)
        if self.y1 <= self.y0:
            self.y1 = self.y0 + 1
        self.pw, self.ph = W - PAD_L - PAD_R, H - PAD_T - PAD_B

    def x(self, e):
        return PAD_L + self.pw * e / self.x1

    def y(self, v):
        f = math.log10(v) if self.log else v
        return PAD_T + self.ph * (1 - (f - self.y0) / (self.y1 - self.y0))

    def ticks(self):
        """Values of the y axis' labels: 1, 2 and 5 per decade, or 1 to 9 when that gives
        fewer than three (log); else five steps."""
        if not self.log:
            return [self.y0 + (self.y1 - self.y0) * k / 4 for k in range(5)]
        for mantissas in ((1, 2, 5), range(1, 10)):
            out = [m * 10.0 ** d for d in range(math.floor(self.y0), math.ceil(self.y1) + 1)
                   for m in mantissas
                   if self.y0 - 1e-9 <= math.log10(m * 10.0 ** d) <= self.y1 + 1e-9]
            if len(out) >= 3:
                break
        return out

    def epoch_ticks(self):
        """Up to five distinct whole epochs from 0 to the last."""
        return sorted({round(self.x1 * k / 4) for k in range(5)})


def _scale(lines):
    pts = [p for _, units in lines for _, tr, va in units for p in tr + va]
    vals = [v for _, v in pts]
    x1 = max(e for e, _ in pts)
    lo, hi = min(vals), max(vals)
    if lo > 0:
        return Scale(x1, lo / 1.1, hi * 1.1)
    return Scale(x1, min(lo, 0.0), hi * 1.05 or 1.0)


def _axes(s):
    ph, pw = s.ph, s.pw
    parts = [f'<line x1="{PAD_L}" y1="{PAD_T + ph}" x2="{PAD_L + pw}" y2="{PAD_T + ph}" '
             'stroke="black"/>',
             f'<line x1="{PAD_L}" y1="{PAD_T}" x2="{PAD_L}" y2="{PAD_T + ph}" stroke="black"/>']
    for v in s.ticks():
        yy = s.y(v)
        parts.append(f'<line x1="{PAD_L - 3}" y1="{yy:.1f}" x2="{PAD_L}" y2="{yy:.1f}" '
                     'stroke="black"/>')
        parts.append(f'<text x="{PAD_L - 5}" y="{yy + 3:.1f}" text-anchor="end">{v:.3g}</text>')
    for ep in s.epoch_ticks():
        parts.append(f'<text x="{s.x(ep):.1f}" y="{PAD_T + ph + 12}" '
                     f'text-anchor="middle">{ep}</text>')
    parts.append(f'<text x="{PAD_L + pw / 2}" y="{PAD_T + ph + 24}" '
                 'text-anchor="middle">epoch</text>')
    return parts


def _polyline(s, pts, colour, dashed):
    d = " ".join(f"{s.x(e):.1f},{s.y(v):.1f}" for e, v in pts)
    dash = ' stroke-dasharray="4 3"' if dashed else ""
    return (f'<polyline fill="none" stroke="{colour}" stroke-width="1.5"{dash} '
            f'points="{d}"/>')


def _legend(names, cols):
    """Colour per unit (two columns) and the two line styles, under the plot."""
    parts, y0 = [], H - PAD_B + 36
    for i, (name, c) in enumerate(zip(names, cols)):
        x, y = PAD_L + (i % 2) * 120, y0 + (i // 2) * 12
        parts.append(f'<rect x="{x}" y="{y - 7}" width="10" height="8" fill="{c}"/>')
        parts.append(f'<text x="{x + 13}" y="{y}">{html.escape(name)}</text>')
    parts.append(f'<text x="{W - PAD_R}" y="{PAD_T - 4}" text-anchor="end">'
                 "solid: train loss, dashed: val L1</text>")
    return parts


def chart(s, label, units, x=0, y=0):
    """One row's chart as an <svg> element at (x, y) of a larger drawing."""
    cols = colours(len(units))
    legend_rows = (len(units) + 1) // 2
    height = H + max(0, legend_rows - 2) * 12
    parts = [f'<svg x="{x}" y="{y}" width="{W}" height="{height}" '
             f'viewBox="0 0 {W} {height}" font-family="sans-serif" font-size="9">',
             f'<rect width="{W}" height="{height}" fill="white"/>',
             f'<text x="{PAD_L}" y="12" font-size="11" font-weight="bold">'
             f"{html.escape(label)}</text>"]
    parts += _axes(s)
    for (_, train, val), c in zip(units, cols):
        if train:
            parts.append(_polyline(s, train, c, False))
        if val:
            parts.append(_polyline(s, val, c, True))
    parts += _legend([n for n, _, _ in units], cols)
    parts.append("</svg>")
    return "\n".join(parts), height


def svg(t, task):
    """The task's charts side by side (an SVG document, ``COLUMNS`` per line), or None when
    no unit of the task has a history."""
    lines = series(t, task)
    if not lines:
        return None
    s = _scale(lines)
    parts, y, row_h = [], 0, 0
    for i, (label, units) in enumerate(lines):
        if i and i % COLUMNS == 0:
            y, row_h = y + row_h, 0
        body, h = chart(s, label, units, x=(i % COLUMNS) * W, y=y)
        parts.append(body)
        row_h = max(row_h, h)
    width, height = min(len(lines), COLUMNS) * W, y + row_h
    head = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="9">')
    title = (f"<title>training loss and validation L1 per epoch, {html.escape(task)} task "
             "(epoch 0: untrained)</title>")
    return "\n".join([head, title, *parts, "</svg>"]) + "\n"
