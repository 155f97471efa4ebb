"""The experiment: data, folds, mixes, one training unit per (task, row, fold), scores, table.

Run folder (every file written through a temporary file + rename):

    RUN/config.json                 the options of the run (a rerun must pass the same)
    RUN/folds.json                  the k-fold manifest (folds.py)
    RUN/mixes.json                  every fold's training slots per mixed row (mix.py)
    RUN/data/...                    cached network inputs and targets (.npy)
    RUN/units/<task>/<row>/<fold>/  model/ (checkpoints, resumed after a kill), scores.json
    RUN/table.md, table.json, index.html, img/   (table.py, report.py)

A unit is done when its scores.json exists; a rerun skips done units and the trainer resumes
an interrupted one from its last epoch, so a killed run finishes with the same table.
Every input (day DNGs, real set) and every file an earlier run left in RUN is checked before
anything is written (runfolder.py: a damaged file is an error naming it and what to do).

:class:`Experiment` only strings the parts together: config.py (the options, resolved),
prepare.py (checks, inputs, folds; the setup files), source.py (the pairs), unit.py (train
and score one unit), table.py and report.py."""

import pathlib

from . import prepare, protocol, report, rows, runfolder, table, unit
from ..atomic import write_json
from .config import ExperimentConfig, ExperimentError, resolve  # noqa: F401
from .prepare import day_images, log  # noqa: F401
from .source import PairSource


class Experiment:
    """One run of the experiment from an ExperimentConfig (resolved at once: a bad option,
    real set or fold file is an error here, before anything is read or written)."""

    def __init__(self, config):
        self.config, self.target_isps = resolve(config)
        self.out = pathlib.Path(self.config.output)
        self.tasks = rows.tasks_of(self.config.task)
        self.rows = rows.select(list(self.config.rows))
        self.inputs = self.plan = self.source = None
        self.report_scenes = []

    def prepare(self):
        """Read and check every input and what an earlier run left in RUN, then write config,
        folds and mixes (nothing is written when anything is bad)."""
        c = self.config
        try:
            import torch
        except ImportError as e:
            raise ExperimentError(f"training needs torch ({e}): pip install day2night[train]") \
                from None
        if c.device == "cuda" and not torch.cuda.is_available():
            raise ExperimentError("--device cuda: torch sees no CUDA device (use --device cpu)")
        prepare.check_config(self.out, c.record())
        self.inputs = prepare.read_inputs(c.day, c.real, self.tasks)
        self.plan = prepare.plan_folds(self.out, c, self.inputs, self.rows)
        prepare.check_run_folder(self.out, self.work(), c.restart_unit, self.inputs.scenes,
                                 c.epochs)
        prepare.write_setup(self.out, c.record(), self.plan, c.restart_unit)
        self.source = PairSource(self.out, c, self.inputs, self.target_isps, self.tasks)
        self.report_scenes, why = report.scenes_to_show(self.plan.splits, c.show)
        if why:
            log(why)
        self._log_setup()

    def _log_setup(self):
        c, i = self.config, self.inputs
        log(
            f"{len(i.scenes)} real scenes, {len(i.days)} day images ({len(i.day_train)} train, "
            f"{len(i.day_val)} val), {c.folds} folds, tasks {', '.join(self.tasks)}"
        )
        for note in protocol.notes(c, i.days, i.scenes, self.target_isps):
            log(note)
        if c.smoke:
            log(
                f"SMOKE RUN: network width {c.width} < 32 (the paper's UNet has 32); "
                "its numbers are not the paper's"
            )

    def work(self):
        """Every unit of the run, in order: (task, row, fold, split)."""
        return rows.work(self.tasks, self.rows, self.plan.splits)

    def run_unit(self, task, row, fold, split, index, total):
        """Train (or resume) and score one unit; skipped when its scores.json exists."""
        c, src = self.config, self.source
        udir = self.out / "units" / task / row.id / fold
        where = f"unit {index}/{total}: task {task}, row {row.id} ({row.label}), fold {fold}"
        if (udir / "scores.json").is_file():
            log(f"{where}: done (scores.json), skipped")
            return
        log(f"{where}: preparing data")
        train_p, val_p = src.train_val(task, row, split, self.plan.mixes)
        test = split["test"] if split else sorted(self.inputs.scenes)
        tests = src.tests(task, test)
        uid = runfolder.unit_id(task, row.id, fold)
        done_epochs = runfolder.check_checkpoints(self.out, uid, udir / "model", c.epochs)
        if done_epochs:
            log(f"{where}: resuming after epoch {done_epochs} of {c.epochs}")
        else:
            log(f"{where}: training {c.epochs} epoch(s)")
        scored = self._train_score(where, task, row, fold, udir, train_p, val_p, tests)
        scored["train_pairs"] = "fresh" if train_p is None else len(train_p)
        scored["val_pairs"] = len(val_p)
        scored["test_scenes"] = list(test)
        write_json(udir / "scores.json", scored)

    def _train_score(self, where, task, row, fold, udir, train_p, val_p, tests):
        from ..train.trainer import CheckpointError

        c = self.config
        if train_p is None:
            days = {n: self.inputs.days[n] for n in self.inputs.day_train}
            folder = self.out / "data" / "day-train"
            train_set = lambda: unit.fresh_set(folder, days, c, task)  # noqa: E731
        else:
            train_set = lambda: unit.fixed_set(train_p, c.patch)  # noqa: E731
        try:
            result = unit.train_unit(c, udir / "model", val_p, train_set)
            log(f"{where}: scoring {len(tests)} test input(s)")
            return unit.score_unit(c, self.out, task, row, fold, tests, result,
                                   self.report_scenes)
        except CheckpointError as e:
            uid = runfolder.unit_id(task, row.id, fold)
            raise runfolder.RunFolderError(f"{e}; {runfolder.unit_advice(self.out, uid)}") \
                from None

    def run(self):
        """The whole run: prepare, every unit, then table.md, table.json and index.html."""
        self.prepare()
        work = self.work()
        for i, (task, row, fold, split) in enumerate(work, 1):
            self.run_unit(task, row, fold, split, i, len(work))
        t = table.build(self.config, self.out, self.plan.splits, len(self.inputs.scenes),
                        len(self.inputs.days))
        table.write(self.out, t)
        report.write(self.out, t, self.tasks, self.report_scenes, self.config.show)
        log(f"wrote {self.out / 'table.md'}, table.json and index.html")
        return t
