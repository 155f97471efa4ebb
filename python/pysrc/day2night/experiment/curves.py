"""Validation L1 per epoch of every unit, as an SVG line chart (one per task): what
index.html shows under the table, also written as RUN/val_l1_<task>.svg. The numbers are
the trainer's (``history[i]["val_loss"]``, the mean L1 over the validation patches after
epoch i; ``initial``: the untrained weights', drawn at epoch 0)."""

import html
import math

COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")
W, H, PAD_L, PAD_R, PAD_T, PAD_B = 640, 300, 56, 190, 24, 36


def series(t, task):
    """[(label, [(epoch, val L1), ...]), ...] of the task's units, in the table's order."""
    out = []
    for r in t["rows"]:
        if r["task"] != task:
            continue
        for u in r["units"]:
            pts = []
            init = (u.get("initial") or {}).get("val_loss")
            if _finite(init):
                pts.append((0, float(init)))
            pts += [(int(h["epoch"]) + 1, float(h["val_loss"])) for h in u.get("history", [])
                    if _finite(h.get("val_loss"))]
            if pts:
                fold = "" if u.get("fold") in (None, "all") else f", fold {u['fold']}"
                out.append((f"{r['label']}{fold}", pts))
    return out


def _finite(v):
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def svg(t, task):
    """The chart (an SVG document), or None when no unit has a history."""
    lines = series(t, task)
    if not lines:
        return None
    xs = [e for _, p in lines for e, _ in p]
    ys = [v for _, p in lines for _, v in p]
    x1, y0, y1 = max(max(xs), 1), 0.0, max(ys) * 1.05 or 1.0
    pw, ph = W - PAD_L - PAD_R, H - PAD_T - PAD_B

    def px(e, v):
        return PAD_L + pw * e / x1, PAD_T + ph * (1 - (v - y0) / (y1 - y0))

    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
             f'viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="11">',
             f'<rect width="{W}" height="{H}" fill="white"/>',
             f'<text x="{PAD_L}" y="14">validation L1 per epoch, {html.escape(task)} task '
             '(epoch 0: untrained)</text>',
             f'<line x1="{PAD_L}" y1="{PAD_T + ph}" x2="{PAD_L + pw}" y2="{PAD_T + ph}" '
             'stroke="black"/>',
             f'<line x1="{PAD_L}" y1="{PAD_T}" x2="{PAD_L}" y2="{PAD_T + ph}" stroke="black"/>']
    for k in range(5):
        v = y0 + (y1 - y0) * k / 4
        _, yy = px(0, v)
        parts.append(f'<text x="{PAD_L - 4}" y="{yy + 4:.1f}" text-anchor="end">{v:.3f}</text>')
        e = round(x1 * k / 4)
        xx, _ = px(e, y0)
        parts.append(f'<text x="{xx:.1f}" y="{PAD_T + ph + 14}" text-anchor="middle">{e}</text>')
    parts.append(f'<text x="{PAD_L + pw / 2}" y="{H - 4}" text-anchor="middle">epoch</text>')
    for i, (label, pts) in enumerate(lines):
        c = COLOURS[i % len(COLOURS)]
        d = " ".join(f"{x:.1f},{y:.1f}" for x, y in (px(e, v) for e, v in pts))
        parts.append(f'<polyline fill="none" stroke="{c}" stroke-width="1.5" points="{d}"/>')
        ly = PAD_T + 4 + 14 * i
        parts.append(f'<line x1="{W - PAD_R + 10}" y1="{ly}" x2="{W - PAD_R + 28}" y2="{ly}" '
                     f'stroke="{c}" stroke-width="2"/>')
        parts.append(f'<text x="{W - PAD_R + 32}" y="{ly + 4}">{html.escape(label)}</text>')
    parts.append("</svg>")
    return "\n".join(parts) + "\n"
