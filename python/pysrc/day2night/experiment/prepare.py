"""Everything the experiment checks before it writes anything (docs/experiment.md): the
options against an earlier run's config.json, the inputs (the real set's manifest and files,
the day DNGs), the folds (an earlier run's folds.json or new ones), and what an earlier run
left in RUN (runfolder.py); then the run folder's setup files. Each function takes what it
reads (the run folder, the config, the inputs) and returns what it makes (:class:`Inputs`,
:class:`Plan`); ``runner.Experiment`` strings them together."""

import dataclasses
import pathlib
import shutil
import sys

import day2night

from ..isos import NOISY_ISOS
from . import folds as folds_mod
from . import mix as mix_mod
from . import protocol, realset, records, release_folds, rows, runfolder
from ..atomic import write_json
from .config import CONFIG_KEYS, PAPER_VALUES, ExperimentError  # noqa: F401
from .protocol import LEGACY_CONFIG


@dataclasses.dataclass
class Inputs:
    """The checked inputs: the day DNGs ({name: path}, split into training and validation
    names) and the real scenes ({id: realset scene})."""

    days: dict
    scenes: dict
    day_train: list
    day_val: list


@dataclasses.dataclass
class Plan:
    """The folds (the fold manifest; ``new``: not read from RUN/folds.json) and the training
    slots of every fold of each mixed row (``mixes``, with the run's synthetic ISOs)."""

    folds: dict
    mixes: dict
    new: bool

    @property
    def splits(self):
        return self.folds["splits"]


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
    for path in days.values():
        try:
            raw = day2night.read_dng(str(path))
        except (OSError, ValueError) as e:
            raise ExperimentError(f"--day: {path}: cannot read the day DNG: {e}") from None
        if raw.data.ndim != 2 or raw.meta.get("cfa_pattern") is None:
            raise ExperimentError(f"--day: {path}: not a Bayer CFA mosaic (synthesis needs "
                                  "one)")


def check_config(out, record, restart=()):
    """An earlier run's config.json in ``out`` against this run's ``record``
    (ExperimentConfig.record): the first option that differs is an error; then the records
    of the units (but those --restart-unit names, ``restart``) and of the cached pairs
    (records.py), which stand in for config.json when it is gone."""
    path = pathlib.Path(out) / "config.json"
    if path.is_file():
        # a key missing from a run made before the protocol options: the value that ran then
        old = {**LEGACY_CONFIG, **runfolder.read_config(path)}
        # (training options absent from both: the paper's; ExperimentConfig.record)
        diff = [k for k in CONFIG_KEYS if old.get(k) != record.get(k)]
        if diff:
            k = diff[0]
            raise ExperimentError(
                f"{out} holds a run made with {k} = {old.get(k, PAPER_VALUES.get(k))!r}, "
                f"not {record.get(k, PAPER_VALUES.get(k))!r}: "
                "rerun with the same options to resume, or choose another -o folder"
            )
    records.check(out, record, restart, path.is_file())


def read_inputs(day, real, tasks):
    """The real set (its manifest, then every file the ``tasks`` read: sizes, SHA-256, DNGs,
    target PNGs) and the day DNGs, all read and checked: the :class:`Inputs`."""
    isos = NOISY_ISOS if "noisy" in tasks else ()
    days = day_images(day)
    try:
        scenes = realset.read_real(real, isos=isos)
        manifest = pathlib.Path(real) / "manifest.jsonl"
        log(f"checking {len(scenes)} real scenes and {len(days)} day images")
        for s in scenes:
            realset.check_scene(s, manifest, clean="clean" in tasks, isos=isos)
    except realset.RealSetError as e:
        raise ExperimentError(str(e)) from None
    check_day_images(days)
    day_train, day_val = mix_mod.split_day_images(days)
    return Inputs(days=days, scenes={s.id: s for s in scenes}, day_train=day_train,
                  day_val=day_val)


def plan_folds(out, config, inputs, run_rows):
    """The folds (an earlier run's RUN/folds.json, checked, or new ones from ``config``'s
    folds, seed and fold file) and the mixes of ``run_rows``: the :class:`Plan`."""
    fpath = pathlib.Path(out) / "folds.json"
    new = not fpath.is_file()
    if not new:
        folds = runfolder.read_folds(fpath, config.folds, config.seed)
        if folds["scenes"] != sorted(inputs.scenes):
            raise ExperimentError(
                f"{fpath}: its scenes differ from the real set's: {runfolder.FOLDS_ADVICE} "
                "(and the units trained on the old folds), or choose another -o folder")
        check_folds_source(fpath, folds, config)
    else:
        folds = release_folds.make_run_folds(sorted(inputs.scenes), config.folds,
                                             seed=config.seed, folds_file=config.folds_file,
                                             folds_sha256=config.folds_sha256)
    mixes = {}
    for r in run_rows:
        if r.per_fold:
            mixes[r.id] = [
                mix_mod.mix(s["train"], inputs.day_train, r.percent, seed=mix_mod.RELEASE_SEED)
                for s in folds["splits"]
            ]
    isos = protocol.run_isos(config.synth_iso, inputs.days, config.seed)
    return Plan(folds=folds, mixes=protocol.mixes_with_isos(mixes, isos), new=new)


def check_folds_source(path, manifest, config):
    """An earlier run's folds.json made the way this run makes its folds: seeded, or from
    the same fold file (its SHA-256, when the manifest records one). A fold file's lists
    are never relabelled as seeded folds, nor the other way round."""
    src = manifest.get("source")
    src = src if isinstance(src, dict) else None
    made = f"the fold file {src.get('file')}" if src else "seeded folds (--seed)"
    now = f"--folds-file {config.folds_file}" if config.folds_file else "seeded folds"
    same = (src is None) == (config.folds_file is None) and (
        src is None or src.get("sha256") in (None, config.folds_sha256))
    if not same:
        raise ExperimentError(
            f"{path}: made from {made}, this run has {now}: rerun with the options that "
            f"made it, or {runfolder.FOLDS_ADVICE} (and the units trained on the old "
            "folds), or choose another -o folder")


def check_run_folder(out, work, restart, scenes, epochs, extra_seeds=()):
    """Every planned unit's scores.json (done units) or checkpoints (the others), and the
    cached data; units named by --restart-unit (``restart``) are not checked (they are
    deleted). ``work``: rows.work's units, also run with each of ``extra_seeds`` (--seeds);
    ``scenes``: the real scenes' ids."""
    out = pathlib.Path(out)
    seeded = [(w, s) for s in (None, *extra_seeds) for w in work
              if s is None or w[1].source != "burst"]  # the burst row has no seed
    ids = [runfolder.unit_id(t, r.id, f, s) for (t, r, f, _), s in seeded]
    for uid in restart:
        if uid not in ids:
            raise ExperimentError(
                f"--restart-unit {uid}: not a unit of this run (TASK/ROW/FOLD, one of: "
                f"{', '.join(ids)})")
    for ((task, row, fold, split), seed), uid in zip(seeded, ids):
        udir = runfolder.unit_dir(out, uid)
        if uid in restart:
            continue
        if (udir / "scores.json").is_file():
            tests = split["test"] if split else sorted(scenes)
            runfolder.read_scores(out, udir / "scores.json", task, row.id, fold,
                                  rows.test_keys(task), tests, seed, epochs)
        elif row.source != "burst":  # the burst row has no checkpoints (burst.py)
            runfolder.check_checkpoints(out, uid, udir / "model", epochs)
    runfolder.check_data(out)


def write_setup(out, record, plan, restart, unit_ids=()):
    """RUN/config.json (``record``), folds.json (new folds only), mixes.json; then the
    folders of the units named by --restart-unit (``restart``) deleted, and the options
    records of the units ``unit_ids`` and of RUN/data written (records.py)."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "config.json", record)
    if plan.new:
        folds_mod.write_folds(out / "folds.json", plan.folds)
    write_json(out / "mixes.json", plan.mixes)
    for uid in restart:
        udir = runfolder.unit_dir(out, uid)
        if udir.exists():
            shutil.rmtree(udir)
            log(f"--restart-unit {uid}: deleted {udir}")
    records.write(out, record, unit_ids)
