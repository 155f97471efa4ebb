"""The rows of the paper's Tables 1 and 2 and the training units each one needs.

A row trained on synthesis only (Day, Day dimmed, Global relight, Ours, Ours on fresh
synthesis) is one model per task, validated on the synthetic validation images and tested on
every real scene (the paper: "the 105 test images"). A row with real data (Ours + 5 % or
10 % real, Supervised) is one model per fold and task, validated on the fold's real
validation scenes and tested on its test scenes; its score is the mean over the folds. The
burst row (the supplementary's burst denoising, noisy task only) trains nothing: each
scene's high-ISO burst averaged and rendered (burst.py), scored on every real scene."""

import dataclasses

from ..isos import NOISY_ISOS


@dataclasses.dataclass(frozen=True)
class Row:
    id: str
    label: str
    source: str  # "synthetic" | "mix" | "fresh" | "untrained" | "burst"
    mode: str = "local"  # synthesis mode of its synthetic data
    percent: float = 0.0  # real share of the training slots ("mix")
    tasks: tuple = ("clean", "noisy")  # the tasks it has a unit in

    @property
    def per_fold(self):
        return self.source == "mix"


ROWS = (
    Row("day", "Day", "synthetic", mode="day"),
    Row("dimmed", "Day dimmed", "synthetic", mode="dimmed"),
    Row("global", "Global relight", "synthetic", mode="global"),
    Row("ours", "Ours", "synthetic", mode="local"),
    Row("mix5", "Ours 95 % + Real 5 %", "mix", percent=5),
    Row("mix10", "Ours 90 % + Real 10 %", "mix", percent=10),
    Row("supervised", "Supervised (k-fold)", "mix", percent=100),
    Row("fresh", "Ours, fresh synthesis", "fresh"),
    Row("burst", "Burst denoising (mean of the high-ISO frames)", "burst", tasks=("noisy",)),
)
BY_ID = {r.id: r for r in ROWS}
#: The initial weights, scored like a trained unit (no training): first in every table, not
#: one of ``--rows`` (every run has it; its units: RUN/units/<task>/untrained/all).
UNTRAINED = Row("untrained", "Untrained (the initial weights)", "untrained")


def with_untrained(rows):
    """``rows`` with the untrained row first when any of them trains a network (a run of
    the burst row alone trains nothing, needs no torch and has no initial weights)."""
    rows = list(rows)
    return [UNTRAINED] + rows if any(r.source != "burst" for r in rows) else rows


def select(ids):
    """Rows by id, in the table's order; unknown ids are an error naming them."""
    if not ids:
        return list(ROWS)
    unknown = [i for i in ids if i not in BY_ID]
    if unknown:
        raise ValueError(
            f"unknown row {unknown[0]!r} (rows: {', '.join(r.id for r in ROWS)})"
        )
    return [r for r in ROWS if r.id in set(ids)]


def tasks_of(task):
    if task == "both":
        return ["clean", "noisy"]
    if task in ("clean", "noisy"):
        return [task]
    raise ValueError(f"task {task!r}: use clean, noisy or both")


def test_keys(task):
    """The inputs each test scene is scored on: the merged raw, or each noisy ISO."""
    return ["clean"] if task == "clean" else list(NOISY_ISOS)


def units(row, splits):
    """(fold name, split) of each unit of ``row`` per task: one per fold of the fold
    manifest's ``splits`` for a row with real data, else one, ``"all"`` (split None)."""
    if row.per_fold:
        return [(str(s["fold"]), s) for s in splits]
    return [("all", None)]


def of_task(rows, task):
    """The rows of ``rows`` that have a unit in ``task`` (the burst row: noisy only)."""
    return [r for r in rows if task in r.tasks]


def for_tasks(rows, task, named):
    """The rows a run of ``task`` (clean, noisy or both) runs: a row of no task of the run is
    dropped from the default rows and refused when named (``named``)."""
    tasks = tasks_of(task)
    off = [r for r in rows if not set(r.tasks) & set(tasks)]
    if named and off:
        raise ValueError(f"--rows {off[0].id}: the {off[0].label} row has the "
                         f"{' and '.join(off[0].tasks)} task only; this run has --task {task}")
    return [r for r in rows if r not in off]


def work(tasks, rows, splits):
    """Every unit of a run, in order: (task, row, fold, split)."""
    return [(task, row, fold, split) for task in tasks for row in of_task(rows, task)
            for fold, split in units(row, splits)]
