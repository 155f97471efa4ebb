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
anything is written (runfolder.py: a damaged file is an error naming it and what to do)."""

import pathlib

from ..isos import NOISY_ISOS
from . import mix as mix_mod
from . import pairs, prepare, presets, protocol, report, rows, runfolder, table
from ..atomic import write_json
from .prepare import CONFIG_KEYS, ExperimentError, day_images, log  # noqa: F401


class Experiment:
    def __init__(self, day, real, out, task="both", epochs=500, device="cpu", seed=0,
                 folds=None, rows_=None, width=32, show=3, restart=(), train_opts=None,
                 **protocol_flags):
        """``protocol_flags``: protocol.for_run's; ``train_opts``: presets.apply's."""
        self.out = pathlib.Path(out)
        self.cfg = {
            "day": str(pathlib.Path(day).resolve()),
            "real": str(pathlib.Path(real).resolve()),
            "task": task,
            "epochs": int(epochs),
            "seed": int(seed),
            "width": int(width),
            "device": device,
        }
        self.workers = presets.apply(self.cfg, train_opts)
        if self.cfg["epochs"] < 1:
            raise ExperimentError(f"--epochs {epochs}: at least 1")
        if self.cfg["width"] < 1:
            raise ExperimentError(f"--width {width}: at least 1 (the paper's network: 32)")
        if device not in ("cpu", "cuda"):
            raise ExperimentError(f"--device {device!r}: use cpu or cuda")
        if not 0 <= self.cfg["seed"] <= 2**32 - 1:
            raise ExperimentError(f"--seed {seed}: use 0 to {2**32 - 1} (numpy's RandomState)")
        if int(show) < 0:
            raise ExperimentError(f"--show {show}: at least 0 (test scenes on index.html)")
        self.target_isps, _ = protocol.for_run(self.cfg, real, folds, **protocol_flags)
        self.restart = list(dict.fromkeys(restart or ()))
        self.tasks = rows.tasks_of(task)
        self.rows = protocol.fresh_rows(rows.select(rows_ or []), self.cfg, bool(rows_))
        self.cfg["rows"] = [r.id for r in self.rows]
        self.show = show
        self.smoke = self.cfg["width"] < 32

    # ---- setup -------------------------------------------------------------------------
    def prepare(self):
        """Read and check every input and what an earlier run left in RUN, then write config,
        folds and mixes (nothing is written when anything is bad)."""
        try:
            import torch
        except ImportError as e:
            raise ExperimentError(f"training needs torch ({e}): pip install day2night[train]") \
                from None
        if self.cfg["device"] == "cuda" and not torch.cuda.is_available():
            raise ExperimentError("--device cuda: torch sees no CUDA device (use --device cpu)")
        prepare.check_config(self)
        prepare.read_inputs(self)
        prepare.plan_folds(self)
        protocol.apply_isos(self)
        prepare.check_run_folder(self)
        prepare.write_setup(self)
        self.report_scenes = self.folds["splits"][0]["test"][: self.show]
        n = len(self.scenes)
        log(
            f"{n} real scenes, {len(self.days)} day images ({len(self.day_train)} train, "
            f"{len(self.day_val)} val), {self.cfg['folds']} folds, tasks {', '.join(self.tasks)}"
        )
        for note in protocol.notes(self):
            log(note)
        if self.smoke:
            log(
                f"SMOKE RUN: network width {self.cfg['width']} < 32 (the paper's UNet has 32); "
                "its numbers are not the paper's"
            )

    # ---- cached pairs ------------------------------------------------------------------
    def real(self, sid, key):
        """(x_path, y_path) of real scene ``sid`` for input key "clean" or an ISO."""
        scene = self.scenes[sid]
        name = f"{sid}_{key}" if key != "clean" else sid
        folder = self.out / "data" / "real"
        iso = None if key == "clean" else int(key)
        return pairs.cached(folder, {key: name}, lambda: {key: self._real_pair(scene, iso)})[key]

    def _real_pair(self, scene, iso):
        try:
            return pairs.real_pair(scene, iso, targets=self.cfg["targets"],
                                   source=self.target_isps.get(scene.id, "day2night"))
        except (pairs.PairError, ValueError) as e:
            raise ExperimentError(str(e)) from None

    def synth(self, mode, name, key):
        """(x_path, y_path) of day image ``name`` synthesized in ``mode`` for input ``key``."""
        folder = self.out / "data" / f"synth-{mode}"
        stem = name.replace("/", "__").rsplit(".", 1)[0]
        names = {}
        if "clean" in self.tasks:
            names["clean"] = stem
        if "noisy" in self.tasks:
            names.update({iso: f"{stem}_{iso}" for iso in NOISY_ISOS})
        seed = self.cfg["seed"]

        def make():
            try:
                return pairs.synth_pairs(self.days[name], mode, seed,
                                         targets=self.cfg["targets"], noise=self.cfg["noise"])
            except (pairs.PairError, ValueError) as e:
                raise ExperimentError(str(e)) from None

        return pairs.cached(folder, names, make)[key]

    def slot_pair(self, slot, task, mode):
        key = "clean" if task == "clean" else slot["iso"]
        if slot["kind"] == "real":
            return self.real(slot["id"], key)
        return self.synth(mode, slot["id"], key)

    # ---- units -------------------------------------------------------------------------
    def units(self, task, row):
        if row.per_fold:
            for s in self.folds["splits"]:
                yield str(s["fold"]), s
        else:
            yield "all", None

    def work(self):
        """Every unit of the run, in order: (task, row, fold, split)."""
        return [
            (task, row, fold, split)
            for task in self.tasks
            for row in self.rows
            for fold, split in self.units(task, row)
        ]

    def train_val(self, task, row, split):
        if row.per_fold:
            fold = split["fold"]
            train = self.mixes[row.id][fold]
            val = mix_mod.real_slots(split["val"])
        else:
            train, val = (protocol.synthetic_slots(self, d) for d in (self.day_train,
                                                                      self.day_val))
        val_p = [self.slot_pair(s, task, row.mode) for s in val]
        if row.source == "fresh":
            return None, val_p
        return [self.slot_pair(s, task, row.mode) for s in train], val_p

    def run_unit(self, task, row, fold, split, index, total):
        run_unit(self, task, row, fold, split, index, total)

    def run(self):
        self.prepare()
        work = self.work()
        for i, (task, row, fold, split) in enumerate(work, 1):
            self.run_unit(task, row, fold, split, i, len(work))
        t = table.build(self)
        table.write(self, t)
        report.write(self, t)
        log(f"wrote {self.out / 'table.md'}, table.json and index.html")
        return t


def run_unit(exp, task, row, fold, split, index, total):
    """Train (or resume) and score one unit; skipped when its scores.json exists."""
    from . import unit

    udir = exp.out / "units" / task / row.id / fold
    done = udir / "scores.json"
    where = f"unit {index}/{total}: task {task}, row {row.id} ({row.label}), fold {fold}"
    if done.is_file():
        log(f"{where}: done (scores.json), skipped")
        return
    log(f"{where}: preparing data")
    train_p, val_p = exp.train_val(task, row, split)
    test = split["test"] if split else sorted(exp.scenes)
    tests = [(sid, k, exp.real(sid, k)) for sid in test for k in rows.test_keys(task)]
    uid = runfolder.unit_id(task, row.id, fold)
    done_epochs = runfolder.check_checkpoints(exp.out, uid, udir / "model",
                                              exp.cfg["epochs"])
    if done_epochs:
        log(f"{where}: resuming after epoch {done_epochs} of {exp.cfg['epochs']}")
    else:
        log(f"{where}: training {exp.cfg['epochs']} epoch(s)")
    from ..train.trainer import CheckpointError

    try:
        result = unit.train_unit(exp, udir, task, row, train_p, val_p)
        log(f"{where}: scoring {len(tests)} test input(s)")
        scored = unit.score_unit(exp, udir, task, row, fold, tests, result)
    except CheckpointError as e:
        raise runfolder.RunFolderError(f"{e}; {runfolder.unit_advice(exp.out, uid)}") \
            from None
    scored["train_pairs"] = "fresh" if train_p is None else len(train_p)
    scored["val_pairs"] = len(val_p)
    scored["test_scenes"] = list(test)
    write_json(done, scored)
