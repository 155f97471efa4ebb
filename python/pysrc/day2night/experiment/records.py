"""What made each unit and the cached pairs, recorded beside them (issue 42 item 9), so that a
resume never mixes settings in one table, even when ``RUN/config.json`` was deleted:

- ``RUN/units/<task>/<row>/<fold>/options.json``: the options that train and score the unit
  (:data:`UNIT_KEYS`: the inputs, seed, folds, protocol, targets, noise, synthetic ISOs, fold
  file and its SHA-256, and the training options), written before it trains;
- ``RUN/data/options.json``: the options that make the cached pairs (:data:`DATA_KEYS`: the
  inputs, seed, target ISP and noise; each input store's header holds its gamma, which
  pairs.check_cached compares).

Before anything is written a rerun compares every record with its own options: a difference
is an error naming the record, the option and the fix. With ``config.json`` gone, the records
stand in for it: the run goes on when they agree with its options (``config.json`` is written
again from them), and a unit folder or cached data without a record (a folder of an earlier
version) is refused, naming the fix, never relabelled."""

import pathlib

from . import runfolder
from ..atomic import write_json
from .config import CONFIG_KEYS, PAPER_VALUES, ExperimentError
from .protocol import LEGACY_CONFIG

UNIT_FORMAT = "day2night-unit-options/1"
DATA_FORMAT = "day2night-data-options/1"
#: The options of a unit (every compared option but the run's task and row list).
UNIT_KEYS = tuple(k for k in CONFIG_KEYS if k not in ("task", "rows"))
#: The options that make a cached pair.
DATA_KEYS = ("day", "real", "seed", "targets", "noise")
NAME = "options.json"


def values(record, keys):
    """``keys``' values of a config record (ExperimentConfig.record), an absent training
    option as the paper's."""
    return {k: record.get(k, PAPER_VALUES.get(k)) for k in keys}


def _old_value(old, k):
    return old.get(k, PAPER_VALUES.get(k, LEGACY_CONFIG.get(k)))


def first_difference(old, record, keys):
    """(key, recorded value, this run's value) of the first of ``keys`` that differs, else
    None."""
    new = values(record, keys)
    for k in keys:
        if _old_value(old, k) != new[k]:
            return k, _old_value(old, k), new[k]
    return None


def _read(path, fmt, advice):
    rec = runfolder.read_object(path, "options record", advice)
    if rec.get("format") != fmt or not isinstance(rec.get("options"), dict):
        raise runfolder.RunFolderError(
            f"{path}: damaged options record: not a {fmt} record; {advice}")
    return rec["options"]


def unit_folders(out):
    """{unit id: folder} of every unit folder: RUN/units/TASK/ROW/FOLD (id TASK/ROW/FOLD)
    and RUN/seeds/S/units/TASK/ROW/FOLD of an extra seed (id seed-S/TASK/ROW/FOLD)."""
    found = {}
    roots = [("", pathlib.Path(out) / "units")]
    roots += [(f"seed-{d.name}/", d / "units")
              for d in sorted((pathlib.Path(out) / "seeds").glob("*")) if d.is_dir()]
    for prefix, root in roots:
        if root.is_dir():
            found.update({prefix + str(p.relative_to(root).as_posix()): p
                          for p in sorted(root.glob("*/*/*")) if p.is_dir()})
    return found


def _has_data(out):
    data = pathlib.Path(out) / "data"
    return data.is_dir() and any(p.name.endswith(".npy") for p in data.rglob("*.npy"))


def check(out, record, restart, has_config):
    """Every unit's and the data's record against this run's ``record``; ``restart``: the
    units --restart-unit deletes (not checked); ``has_config``: RUN/config.json exists."""
    out = pathlib.Path(out)
    fix = ("rerun with the options it records, or choose another -o folder"
           if has_config else "rerun with the options it records (RUN/config.json is gone; "
           "a finished run's table.json records them under \"config\"), or choose another "
           "-o folder")
    for uid, folder in unit_folders(out).items():
        if uid in restart:
            continue
        advice = runfolder.unit_advice(out, uid)
        path = folder / NAME
        if not path.is_file():
            if has_config:
                continue  # a unit of an earlier version: config.json vouches for it
            raise ExperimentError(
                f"{folder}: RUN/config.json is gone and this unit records no options (a run "
                f"folder of an earlier version): restore config.json from table.json's "
                f"\"config\", or {advice}")
        diff = first_difference(_read(path, UNIT_FORMAT, advice), record, UNIT_KEYS)
        if diff:
            raise ExperimentError(
                f"{path}: the unit was made with {diff[0]} = {diff[1]!r}, not {diff[2]!r}: "
                f"{fix}, or {advice}")
    _check_data(out, record, has_config)


def _check_data(out, record, has_config):
    path = out / "data" / NAME
    advice = f"delete {out / 'data'} to have the pairs made again"
    if not path.is_file():
        if _has_data(out) and not has_config:
            raise ExperimentError(
                f"{out / 'data'}: RUN/config.json is gone and the cached pairs record no "
                f"options (a run folder of an earlier version): restore config.json from "
                f"table.json's \"config\", or {advice}")
        return
    diff = first_difference(_read(path, DATA_FORMAT, advice), record, DATA_KEYS)
    if diff:
        raise ExperimentError(
            f"{path}: the cached pairs were made with {diff[0]} = {diff[1]!r}, not "
            f"{diff[2]!r}: rerun with the options it records, or {advice}")


def write(out, record, unit_ids):
    """The records of the run's units ``unit_ids`` (TASK/ROW/FOLD) and of RUN/data, each
    written when absent (a present one equals ``record``: :func:`check`)."""
    out = pathlib.Path(out)
    for uid in unit_ids:
        path = runfolder.unit_dir(out, uid) / NAME
        if not path.is_file():
            write_json(path, {"format": UNIT_FORMAT, "unit": uid,
                              "options": values(record, UNIT_KEYS)})
    path = out / "data" / NAME
    if not path.is_file():
        write_json(path, {"format": DATA_FORMAT, "options": values(record, DATA_KEYS)})
