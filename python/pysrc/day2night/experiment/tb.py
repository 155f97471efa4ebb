"""The learning curves as TensorBoard event files, so a run opens in ``tensorboard --logdir
RUN/tb``: one run per unit, RUN/tb/<task>/<row>/<fold>, and .../<fold>/seed-<S> when the row
was trained with several seeds (``--seeds N``).

Written from the units' histories in table.json when the report is written (report.py), not
by the trainer: a resumed or rerun run gets the same curves without duplicated events, and
the trainer has no dependency on TensorBoard. Scalars per epoch (step = epoch + 1; step 0 is
the untrained network, validation only): ``train/loss`` (history ``loss``), ``val/l1``
(``val_loss``) and ``val/psnr`` (``val_psnr``, dB). The tree is written in a temporary folder
and renamed over RUN/tb, so a rerun replaces it whole. Event files carry the time they were
written (not reproducible byte for byte, unlike table.json).

Needs the ``tensorboard`` package (the ``train`` extra); without it :func:`write` writes
nothing and says why."""

import pathlib
import shutil
import time

try:
    from tensorboard.compat.proto.event_pb2 import Event
    from tensorboard.compat.proto.summary_pb2 import Summary
    from tensorboard.summary.writer.event_file_writer import EventFileWriter

    MISSING = None
except ImportError as _e:  # the core package does not need it
    Event = Summary = EventFileWriter = None
    MISSING = str(_e)

from ..atomic import create_temp_dir
from .curves import finite

#: (tag, history key) of the scalars, per epoch.
SCALARS = (("train/loss", "loss"), ("val/l1", "val_loss"), ("val/psnr", "val_psnr"))


def unit_dir(task, row, u, seeded):
    """A unit's run folder under RUN/tb (``seeded``: the row has several seeds)."""
    parts = [task, row, str(u.get("fold", "all"))]
    if seeded and u.get("seed") is not None:
        parts.append(f"seed-{u['seed']}")
    return pathlib.PurePosixPath(*parts)


def points(u):
    """{tag: [(step, value), ...]} of one unit's history (finite values only)."""
    out = {tag: [] for tag, _ in SCALARS}
    init = u.get("initial") or {}
    for tag, key in SCALARS:
        if finite(init.get(key)):
            out[tag].append((0, float(init[key])))
        for h in u.get("history") or []:
            if finite(h.get(key)):
                out[tag].append((int(h["epoch"]) + 1, float(h[key])))
    return out


def _write_unit(folder, pts, wall):
    folder.mkdir(parents=True, exist_ok=True)
    w = EventFileWriter(str(folder))
    try:
        for tag, series in pts.items():
            for step, v in series:
                summary = Summary(value=[Summary.Value(tag=tag, simple_value=v)])
                w.add_event(Event(wall_time=wall, step=step, summary=summary))
    finally:
        w.close()


def runs(t):
    """[(relative folder, points), ...] of every unit of table ``t`` with a history."""
    out = []
    for r in t.get("rows", []):
        units = r.get("units", [])
        seeded = len({u.get("seed") for u in units if u.get("seed") is not None}) > 1
        for u in units:
            pts = points(u)
            if any(pts.values()):
                out.append((unit_dir(r["task"], r["row"], u, seeded), pts))
    return out


def write(out, t):
    """RUN/tb of the table ``t``: the number of units written, or a string saying why
    nothing was written (tensorboard not installed, or no unit has a history)."""
    if MISSING is not None:
        return (f"tb/ not written: the tensorboard package is not installed ({MISSING}); "
                "pip install tensorboard (the train extra has it) and rerun to get it")
    todo = runs(t)
    if not todo:
        return "tb/ not written: no unit has a training history"
    out = pathlib.Path(out)
    tmp = create_temp_dir(out, ".tb.")
    try:
        wall = time.time()
        for rel, pts in todo:
            _write_unit(tmp / rel, pts, wall)
        final, old = out / "tb", out / f"{tmp.name}.old"
        if final.exists():
            final.rename(old)
        tmp.rename(final)
        shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return len(todo)
