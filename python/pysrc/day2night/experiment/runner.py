"""The experiment: data, folds, mixes, one training unit per (task, row, fold), scores, table.

Run folder (every file written through a temporary file + rename):

    RUN/config.json                 the options of the run (a rerun must pass the same)
    RUN/folds.json                  the k-fold manifest (folds.py)
    RUN/mixes.json                  every fold's training slots per mixed row (mix.py)
    RUN/data/...                    cached network inputs and targets (.npy)
    RUN/units/<task>/<row>/<fold>/  model/ (checkpoints, resumed after a kill), scores.json
                                    (row "untrained": the initial weights, scores.json only)
    RUN/seeds/<S>/units/...         the same per extra training seed S of --seeds N > 1
    RUN/table.md, table.json, index.html, img/   (table.py, report.py)
    RUN/left_out.json               rows the inputs cannot give, and why (burst.py)
    RUN/log.txt                     every line of the log and every warning (runlog.py)

A unit is done when its scores.json exists; a rerun skips done units and the trainer resumes
an interrupted one from its last epoch, so a killed run finishes with the same table.
Every input (day DNGs, real set) and every file an earlier run left in RUN is checked before
anything is written (runfolder.py: a damaged file is an error naming it and what to do).

:class:`Experiment` only strings the parts together: config.py (the options, resolved),
prepare.py (checks, inputs, folds; the setup files), source.py (the pairs), unit.py (train
and score one unit), table.py and report.py."""

import dataclasses
import pathlib

from . import burst, distributed, prepare, protocol, report, rows, runfolder, runlock, runlog
from . import table, unit
from ..atomic import write_json
from .config import ExperimentConfig, ExperimentError, resolve  # noqa: F401
from .prepare import day_images, log  # noqa: F401
from .source import PairSource
from ..train._torch import available as torch_available
from ..train._torch import missing as torch_missing
from ..train._torch import torch
from ..train.trainer import CheckpointError


class Experiment:
    """One run of the experiment from an ExperimentConfig (resolved at once: a bad option,
    real set or fold file is an error here, before anything is read or written)."""

    def __init__(self, config):
        if config.ray is not None:  # --ray: its options and ray, before anything is read
            distributed.check(config)
            distributed.import_ray()
        self.config, self.target_isps = resolve(config)
        self.out = pathlib.Path(self.config.output)
        self.tasks = rows.tasks_of(self.config.task)
        self.rows = rows.select(list(self.config.rows))
        self.inputs = self.plan = self.source = None
        self.report_scenes = []
        self.left_out = []  # [{"task", "row", "why"}]: rows the inputs cannot give (burst.py)
        self.runlog = None  # runlog.RunLog while run() runs: RUN/log.txt
        self.lock = None  # RUN/driver.lock while run() runs (runlock.py)

    def prepare(self):
        """Read and check every input and what an earlier run left in RUN, then write config,
        folds and mixes (nothing is written when anything is bad)."""
        c = self.config
        if any(r.source != "burst" for r in self.rows):  # the burst row trains nothing
            if not torch_available():
                raise ExperimentError(f"training needs torch ({torch_missing()})")
            if c.device == "cuda" and not torch.cuda.is_available():
                raise ExperimentError("--device cuda: torch sees no CUDA device (use --device "
                                      "cpu)")
        prepare.check_config(self.out, c.record(), c.restart_unit)
        self.inputs = prepare.read_inputs(c.day, c.real, self.tasks)
        self.rows, self.left_out = burst.burst_rows(c, self.inputs, self.rows)
        self.plan = prepare.plan_folds(self.out, c, self.inputs, self.rows)
        prepare.check_run_folder(self.out, self.work(), c.restart_unit, self.inputs.scenes,
                                 c.epochs, c.seed_list[1:])
        prepare.write_setup(self.out, c.record(), self.plan, c.restart_unit,
                            [runfolder.unit_id(t, r.id, f, s)
                             for s, t, r, f, _ in self.seeded_work()])
        write_json(self.out / "left_out.json", self.left_out)
        if self.runlog is not None:
            self.runlog.open(self.out / "log.txt")
        for gone in self.left_out:
            log(f"row {gone['row']} ({gone['task']} task) left out: {gone['why']}")
        self.source = PairSource(self.out, c, self.inputs, self.target_isps, self.tasks)
        self.report_scenes, why = report.scenes_to_show(self.plan.splits, c.show)
        if why:
            log(why)
        log_setup(self.config, self.inputs, self.tasks, self.target_isps)

    def work(self):
        """Every unit of one seed, in order: (task, row, fold, split); the untrained row
        first in each task."""
        return rows.work(self.tasks, rows.with_untrained(self.rows), self.plan.splits)

    def seeded_work(self):
        """Every unit of the run: (seed, task, row, fold, split), the units of --seed first
        (seed None: RUN/units/...), then those of each extra seed of --seeds."""
        return [(s, *w) for s in (None, *self.config.seed_list[1:]) for w in self.work()
                if s is None or w[1].source != "burst"]  # the burst row has no seed

    def run_unit(self, seed, task, row, fold, split, index, total):
        """Train (or resume) and score one unit; skipped when its scores.json exists."""
        c, src = self.config, self.source
        uid = runfolder.unit_id(task, row.id, fold, seed)
        udir = runfolder.unit_dir(self.out, uid)
        where = f"unit {index}/{total}: task {task}, row {row.id} ({row.label}), fold {fold}"
        if c.seeds > 1:
            where += f", seed {c.seed if seed is None else seed}"
        self.current_unit = where  # named by __main__'s line of an error, not a resume
        if (udir / "scores.json").is_file():
            log(f"{where}: done (scores.json), skipped")
            return
        if row.source == "burst":  # no training (burst.py)
            return burst.run_unit(self.out, c, self.inputs, self.target_isps, src,
                                  self.report_scenes, lambda m: log(f"{where}: {m}"))
        cs = c if seed is None else dataclasses.replace(c, seed=seed)
        shown = self.report_scenes if seed is None else []
        test = split["test"] if split else sorted(self.inputs.scenes)
        if row.source == "untrained":
            log(f"{where}: scoring the initial weights on {len(test)} test scene(s)")
            scored = unit.score_untrained(cs, self.out, task, row, fold, src.tests(task, test),
                                          shown)
            scored.update(train_pairs=0, val_pairs=0)
        else:
            log(f"{where}: preparing data")
            train_p, val_p = src.train_val(task, row, split, self.plan.mixes)
            tests = src.tests(task, test)
            done_epochs = runfolder.check_checkpoints(self.out, uid, udir / "model", c.epochs)
            if done_epochs:
                log(f"{where}: resuming after epoch {done_epochs} of {c.epochs}")
            else:
                log(f"{where}: training {c.epochs} epoch(s)")
            scored = self._train_score(where, cs, uid, (task, row, fold), udir, (train_p, val_p),
                                       (tests, shown))
            scored["train_pairs"] = "fresh" if train_p is None else len(train_p)
            scored["val_pairs"] = len(val_p)
        scored["test_scenes"] = list(test)
        if seed is not None:
            scored["seed"] = seed
        write_json(udir / "scores.json", scored)

    def _train_score(self, where, c, uid, unit_key, udir, data, testing):
        """Train the unit ``unit_key`` (task, row, fold) under the config ``c`` (its seed) on
        ``data`` (training pairs, or None for fresh synthesis; validation pairs), then score
        it: ``testing`` = (the test inputs, the scenes whose images the report shows)."""
        (task, row, fold), (train_p, val_p), (tests, report_scenes) = unit_key, data, testing
        if train_p is None:
            days = {n: self.inputs.days[n] for n in self.inputs.day_train}
            folder = self.out / "data" / "day-train"
            train_set = lambda: unit.fresh_set(folder, days, c, task)  # noqa: E731
        else:
            train_set = lambda: unit.fixed_set(train_p, c.patch)  # noqa: E731
        try:
            result = unit.train_unit(c, udir / "model", val_p, train_set)
            log(f"{where}: scoring {len(tests)} test input(s)")
            return unit.score_unit(c, self.out, task, row, fold, tests, result, report_scenes)
        except CheckpointError as e:
            raise runfolder.RunFolderError(f"{e}; {runfolder.unit_advice(self.out, uid)}") \
                from None

    def run(self):
        """The whole run: prepare, every unit, then table.md, table.json and index.html;
        its stderr and warnings logged (runlog.py: RUN/log.txt, each warning kind printed
        once, with its count at the end)."""
        with runlog.capture() as self.runlog:
            try:
                if self.out.is_dir():  # one driver at a time (a new folder: once made)
                    self.lock = runlock.acquire(self.out)
                return self._run()
            finally:
                self.runlog = None
                runlock.release(self.lock)
                self.lock = None

    def _run(self):
        self.prepare()
        self.lock = self.lock or runlock.acquire(self.out)
        work = self.seeded_work()
        if self.config.ray is not None:  # the units as Ray tasks (distributed.py)
            distributed.run(self, work)
        else:
            for i, (seed, task, row, fold, split) in enumerate(work, 1):
                self.run_unit(seed, task, row, fold, split, i, len(work))
        self.current_unit = None
        return write_results(self)


def write_results(exp):
    """table.json, table.md and index.html of the run ``exp`` (its units done): everything
    built before anything is written, so the three always come from one run."""
    t = table.build(exp.config, exp.out, exp.plan.splits, len(exp.inputs.scenes),
                    len(exp.inputs.days), left_out=exp.left_out)
    md = table.markdown(t)
    page = report.build(exp.out, t, exp.tasks, exp.report_scenes, exp.config.show)
    table.write(exp.out, t, md)
    report.write_built(exp.out, t, page)
    log(f"wrote {exp.out / 'table.md'}, table.json and index.html")
    return t


def log_setup(c, i, tasks, target_isps):
    """The run's opening lines: what it runs on, the protocol's notes, the seeds and how it
    differs from the paper (``c`` the config, ``i`` prepare.Inputs)."""
    log(
        f"{len(i.scenes)} real scenes, {len(i.days)} day images ({len(i.day_train)} train, "
        f"{len(i.day_val)} val), {c.folds} folds, tasks {', '.join(tasks)}"
    )
    for note in protocol.notes(c, i.days, i.scenes, target_isps):
        log(note)
    if c.seeds > 1:
        log(f"training seeds {', '.join(map(str, c.seed_list))} (folds and synthetic data "
            f"of seed {c.seed})")
    if c.label == "smoke":
        log(
            f"SMOKE RUN: network width {c.width} < 32 (the paper's UNet has 32); "
            "its numbers are not the paper's"
        )
    elif c.label != "paper":
        what = "MINI PRESET" if c.label == "mini" else "CUSTOM SETTINGS"
        log(f"{what}: network width {c.width}, {c.epochs} epochs (the paper's: 32, 500); "
            "its numbers are not the paper's")
