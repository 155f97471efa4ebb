"""Everything the experiment checks before it writes anything (docs/experiment.md): the
options against an earlier run's config.json, the inputs (the real set's manifest and files,
the day DNGs), the folds (an earlier run's folds.json or new ones), and what an earlier run
left in RUN (runfolder.py); then the run folder's setup files. Functions of the
``runner.Experiment`` they prepare."""

import pathlib
import shutil
import sys

from ..isos import NOISY_ISOS
from . import folds as folds_mod
from . import mix as mix_mod
from . import realset, rows, runfolder
from ..atomic import write_json
from .protocol import LEGACY_CONFIG
from .presets import DEFAULTS  # the paper's training options, absent from config.json

CONFIG_KEYS = ("day", "real", "task", "epochs", "seed", "folds", "width", "device", "rows",
               "protocol", "targets", "noise", "synth_iso", "folds_file", "folds_sha256",
               "patch", "batch", "lr", "amp", "channels_last")


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


def check_day_images(days):
    """Read every day DNG (a file that is no DNG, or no CFA mosaic, is an error naming it)."""
    import day2night

    for path in days.values():
        try:
            raw = day2night.read_dng(str(path))
        except (OSError, ValueError) as e:
            raise ExperimentError(f"--day: {path}: cannot read the day DNG: {e}") from None
        if raw.data.ndim != 2 or raw.meta.get("cfa_pattern") is None:
            raise ExperimentError(f"--day: {path}: not a Bayer CFA mosaic (synthesis needs "
                                  "one)")


def check_config(exp):
    path = exp.out / "config.json"
    if path.is_file():
        # a key missing from a run made before the protocol options: the value that ran then
        old = {**LEGACY_CONFIG, **runfolder.read_config(path)}
        # (training options absent from both: the paper's; presets.config)
        diff = [k for k in CONFIG_KEYS if old.get(k) != exp.cfg.get(k)]
        if diff:
            k = diff[0]
            raise ExperimentError(
                f"{exp.out} holds a run made with {k} = {old.get(k, DEFAULTS.get(k))!r}, "
                f"not {exp.cfg.get(k, DEFAULTS.get(k))!r}: "
                "rerun with the same options to resume, or choose another -o folder"
            )


def read_inputs(exp):
    """The real set (its manifest, then every file the tasks read: sizes, SHA-256, DNGs,
    target PNGs) and the day DNGs, all read and checked."""
    isos = NOISY_ISOS if "noisy" in exp.tasks else ()
    exp.days = day_images(exp.cfg["day"])
    try:
        scenes = realset.read_real(exp.cfg["real"], isos=isos)
        manifest = pathlib.Path(exp.cfg["real"]) / "manifest.jsonl"
        log(f"checking {len(scenes)} real scenes and {len(exp.days)} day images")
        for s in scenes:
            realset.check_scene(s, manifest, clean="clean" in exp.tasks, isos=isos)
    except realset.RealSetError as e:
        raise ExperimentError(str(e)) from None
    exp.scenes = {s.id: s for s in scenes}
    check_day_images(exp.days)
    exp.day_train, exp.day_val = mix_mod.split_day_images(exp.days)


def plan_folds(exp):
    """The folds (an earlier run's folds.json, checked, or new ones) and the mixes."""
    fpath = exp.out / "folds.json"
    exp.new_folds = not fpath.is_file()
    if not exp.new_folds:
        exp.folds = runfolder.read_folds(fpath, exp.cfg["folds"], exp.cfg["seed"])
        if exp.folds["scenes"] != sorted(exp.scenes):
            raise ExperimentError(
                f"{fpath}: its scenes differ from the real set's: {runfolder.FOLDS_ADVICE} "
                "(and the units trained on the old folds), or choose another -o folder")
    else:
        exp.folds = folds_mod.make_run_folds(
            sorted(exp.scenes), exp.cfg["folds"], seed=exp.cfg["seed"],
            folds_file=exp.cfg.get("folds_file"))
    exp.mixes = {}
    for r in exp.rows:
        if r.per_fold:
            exp.mixes[r.id] = [
                mix_mod.mix(s["train"], exp.day_train, r.percent, seed=mix_mod.RELEASE_SEED)
                for s in exp.folds["splits"]
            ]


def check_run_folder(exp):
    """Every planned unit's scores.json (done units) or checkpoints (the others), and the
    cached data; units named by --restart-unit are not checked (they are deleted)."""
    work = exp.work()
    ids = [runfolder.unit_id(t, r.id, f) for t, r, f, _ in work]
    for uid in exp.restart:
        if uid not in ids:
            raise ExperimentError(
                f"--restart-unit {uid}: not a unit of this run (TASK/ROW/FOLD, one of: "
                f"{', '.join(ids)})")
    for (task, row, fold, split), uid in zip(work, ids):
        udir = exp.out / "units" / task / row.id / fold
        if uid in exp.restart:
            continue
        if (udir / "scores.json").is_file():
            tests = split["test"] if split else sorted(exp.scenes)
            runfolder.read_scores(exp.out, udir / "scores.json", task, row.id, fold,
                                  rows.test_keys(task), tests)
        else:
            runfolder.check_checkpoints(exp.out, uid, udir / "model", exp.cfg["epochs"])
    runfolder.check_data(exp.out)


def write_setup(exp):
    exp.out.mkdir(parents=True, exist_ok=True)
    write_json(exp.out / "config.json", exp.cfg)
    if exp.new_folds:
        folds_mod.write_folds(exp.out / "folds.json", exp.folds)
    write_json(exp.out / "mixes.json", exp.mixes)
    for uid in exp.restart:
        udir = exp.out / "units" / uid
        if udir.exists():
            shutil.rmtree(udir)
            log(f"--restart-unit {uid}: deleted {udir}")
