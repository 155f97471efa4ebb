"""The experiment: data, folds, mixes, one training unit per (task, row, fold), scores, table.

Run folder (every file written through a temporary file + rename):

    RUN/config.json                 the options of the run (a rerun must pass the same)
    RUN/folds.json                  the k-fold manifest (folds.py)
    RUN/mixes.json                  every fold's training slots per mixed row (mix.py)
    RUN/data/...                    cached network inputs and targets (.npy)
    RUN/units/<task>/<row>/<fold>/  model/ (checkpoints, resumed after a kill), scores.json
    RUN/table.md, table.json, index.html, img/   (table.py, report.py)

A unit is done when its scores.json exists; a rerun skips done units and the trainer resumes
an interrupted one from its last epoch, so a killed run finishes with the same table."""

import json
import pathlib
import sys

from . import folds as folds_mod
from . import mix as mix_mod
from . import pairs, realset, report, rows, table
from .atomic import write_json

CONFIG_KEYS = ("day", "real", "task", "epochs", "seed", "folds", "width", "device", "rows")


class ExperimentError(ValueError):
    """Bad input of the experiment (the message names the file, scene or option)."""


def log(msg):
    print(f"[experiment] {msg}", file=sys.stderr, flush=True)


def day_images(day_dir):
    root = pathlib.Path(day_dir)
    if not root.is_dir():
        raise ExperimentError(f"--day {root}: not a folder of day DNGs")
    files = sorted(p for p in root.rglob("*") if p.is_file() and p.suffix.lower() == ".dng")
    if len(files) < 2:
        raise ExperimentError(
            f"--day {root}: {len(files)} day DNG(s); synthetic training needs at least 2 "
            "(the release: 70, the first 60 sorted train and the last 10 validate)"
        )
    return {p.relative_to(root).as_posix(): p for p in files}


class Experiment:
    def __init__(self, day, real, out, task="both", epochs=500, device="cpu", seed=0,
                 folds=3, rows_=None, width=32, show=3):
        self.out = pathlib.Path(out)
        self.cfg = {
            "day": str(pathlib.Path(day).resolve()),
            "real": str(pathlib.Path(real).resolve()),
            "task": task,
            "epochs": int(epochs),
            "seed": int(seed),
            "folds": int(folds),
            "width": int(width),
            "device": device,
            "rows": [r.id for r in rows.select(rows_ or [])],
        }
        if self.cfg["epochs"] < 1:
            raise ExperimentError(f"--epochs {epochs}: at least 1")
        if self.cfg["width"] < 1:
            raise ExperimentError(f"--width {width}: at least 1 (the paper's network: 32)")
        if device not in ("cpu", "cuda"):
            raise ExperimentError(f"--device {device!r}: use cpu or cuda")
        self.tasks = rows.tasks_of(task)
        self.rows = rows.select(rows_ or [])
        self.show = show
        self.smoke = self.cfg["width"] < 32

    # ---- setup -------------------------------------------------------------------------
    def check_config(self):
        path = self.out / "config.json"
        if path.is_file():
            try:
                old = json.loads(path.read_text(encoding="utf-8"))
            except ValueError as e:
                raise ExperimentError(f"{path}: unreadable ({e})") from None
            diff = [k for k in CONFIG_KEYS if old.get(k) != self.cfg[k]]
            if diff:
                k = diff[0]
                raise ExperimentError(
                    f"{self.out} holds a run made with {k} = {old.get(k)!r}, not {self.cfg[k]!r}: "
                    "rerun with the same options to resume, or choose another -o folder"
                )

    def prepare(self):
        """Read and check every input, then write config, folds and mixes (nothing is
        written when an input is bad)."""
        try:
            import torch
        except ImportError as e:
            raise ExperimentError(f"training needs torch ({e}): pip install day2night[train]") \
                from None
        if self.cfg["device"] == "cuda" and not torch.cuda.is_available():
            raise ExperimentError("--device cuda: torch sees no CUDA device (use --device cpu)")
        self.check_config()
        isos = (1600, 3200) if "noisy" in self.tasks else ()
        try:
            self.scenes = {s.id: s for s in realset.read_real(self.cfg["real"], isos=isos)}
        except realset.RealSetError as e:
            raise ExperimentError(str(e)) from None
        self.days = day_images(self.cfg["day"])
        self.day_train, self.day_val = mix_mod.split_day_images(self.days)
        fpath = self.out / "folds.json"
        new_folds = not fpath.is_file()
        if not new_folds:
            self.folds = folds_mod.read_folds(fpath)
            if self.folds["scenes"] != sorted(self.scenes):
                raise ExperimentError(f"{fpath}: its scenes differ from the real set's")
        else:
            self.folds = folds_mod.make_folds(
                sorted(self.scenes), self.cfg["folds"], seed=self.cfg["seed"]
            )
        self.mixes = {}
        for r in self.rows:
            if r.per_fold:
                self.mixes[r.id] = [
                    mix_mod.mix(s["train"], self.day_train, r.percent, seed=mix_mod.RELEASE_SEED)
                    for s in self.folds["splits"]
                ]
        self.out.mkdir(parents=True, exist_ok=True)
        write_json(self.out / "config.json", self.cfg)
        if new_folds:
            folds_mod.write_folds(fpath, self.folds)
        write_json(self.out / "mixes.json", self.mixes)
        self.report_scenes = self.folds["splits"][0]["test"][: self.show]
        n = len(self.scenes)
        log(
            f"{n} real scenes, {len(self.days)} day images ({len(self.day_train)} train, "
            f"{len(self.day_val)} val), {self.cfg['folds']} folds, tasks {', '.join(self.tasks)}"
        )
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
            return pairs.real_pair(scene, iso)
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
            names.update({1600: f"{stem}_1600", 3200: f"{stem}_3200"})
        seed = self.cfg["seed"]

        def make():
            try:
                return pairs.synth_pairs(self.days[name], mode, seed)
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

    def train_val(self, task, row, split):
        if row.per_fold:
            fold = split["fold"]
            train = self.mixes[row.id][fold]
            val = mix_mod.real_slots(split["val"])
        else:
            train = mix_mod.synthetic_slots(self.day_train)
            val = mix_mod.synthetic_slots(self.day_val)
        val_p = [self.slot_pair(s, task, row.mode) for s in val]
        if row.source == "fresh":
            return None, val_p
        return [self.slot_pair(s, task, row.mode) for s in train], val_p

    def run_unit(self, task, row, fold, split, index, total):
        from . import unit

        udir = self.out / "units" / task / row.id / fold
        done = udir / "scores.json"
        where = f"unit {index}/{total}: task {task}, row {row.id} ({row.label}), fold {fold}"
        if done.is_file():
            log(f"{where}: done (scores.json), skipped")
            return
        log(f"{where}: preparing data")
        train_p, val_p = self.train_val(task, row, split)
        test = split["test"] if split else sorted(self.scenes)
        tests = [(sid, k, self.real(sid, k)) for sid in test for k in rows.test_keys(task)]
        last = udir / "model" / "last.pt"
        if last.is_file():
            from ..train.trainer import load_checkpoint

            done_epochs = int(load_checkpoint(str(last))["epoch"]) + 1
            log(f"{where}: resuming after epoch {done_epochs} of {self.cfg['epochs']}")
        else:
            log(f"{where}: training {self.cfg['epochs']} epoch(s)")
        result = unit.train_unit(self, udir, task, row, train_p, val_p)
        log(f"{where}: scoring {len(tests)} test input(s)")
        scored = unit.score_unit(self, udir, task, row, fold, tests, result)
        scored["train_pairs"] = "fresh" if train_p is None else len(train_p)
        scored["val_pairs"] = len(val_p)
        scored["test_scenes"] = list(test)
        write_json(done, scored)

    def run(self):
        self.prepare()
        work = [
            (task, row, fold, split)
            for task in self.tasks
            for row in self.rows
            for fold, split in self.units(task, row)
        ]
        for i, (task, row, fold, split) in enumerate(work, 1):
            self.run_unit(task, row, fold, split, i, len(work))
        t = table.build(self)
        table.write(self, t)
        report.write(self, t)
        log(f"wrote {self.out / 'table.md'}, table.json and index.html")
        return t
