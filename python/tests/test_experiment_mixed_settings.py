"""One table, one set of settings (issue 42 item 9): the options that made each unit and the
cached pairs are recorded beside them (experiment/records.py), and a resume compares them,
also when RUN/config.json was deleted (the docs' advice for a damaged one): a rerun with
other options is refused naming the record and the fix, never relabelled."""

import json
import pickle

import pytest

from conftest import need_torch
from day2night.experiment import prepare, records
from day2night.experiment.config import ExperimentError
from test_experiment_protocol import experiment, release_lists, tiny_real_set

RELEASE = {"day": "/d", "real": "/r", "task": "clean", "epochs": 1, "seed": 0, "folds": 3,
           "width": 4, "device": "cpu", "rows": ["mix5"], "protocol": "release",
           "targets": "release", "noise": "release", "synth_iso": "release",
           "folds_file": "/k.p", "folds_sha256": "ab" * 32}
OURS = {**RELEASE, "protocol": "day2night", "targets": "day2night", "noise": "day2night",
        "synth_iso": "alternate", "folds_file": None, "folds_sha256": None,
        "rows": ["mix5", "ours"]}


def made(tmp_path, record=RELEASE, units=("clean/mix5/0",)):
    out = tmp_path / "run"
    records.write(out, record, units)
    (out / "data" / "real").mkdir(parents=True)
    (out / "data" / "real" / "000.in.npy").write_bytes(b"")
    return out


def test_the_records_hold_what_made_the_units_and_the_pairs(tmp_path):
    out = made(tmp_path)
    unit = json.loads((out / "units" / "clean" / "mix5" / "0" / "options.json").read_text())
    assert unit["format"] == records.UNIT_FORMAT and unit["unit"] == "clean/mix5/0"
    assert unit["options"]["targets"] == "release"
    assert unit["options"]["patch"] == 64  # a training option at the paper's value, explicit
    assert "rows" not in unit["options"] and "task" not in unit["options"]
    data = json.loads((out / "data" / "options.json").read_text())
    assert data["options"] == {"day": "/d", "real": "/r", "seed": 0, "targets": "release",
                               "noise": "release"}
    for has_config in (True, False):
        records.check(out, RELEASE, (), has_config)  # the same options: resumed


@pytest.mark.parametrize("has_config", [True, False])
def test_other_options_are_refused_naming_the_record(tmp_path, has_config):
    out = made(tmp_path)
    path = out / "units" / "clean" / "mix5" / "0" / "options.json"
    with pytest.raises(ExperimentError, match=rf"{path}: the unit was made with protocol = "
                       r"'release', not 'day2night': rerun with the options it records.*"
                       r"--restart-unit clean/mix5/0"):
        records.check(out, OURS, (), has_config)
    # the unit --restart-unit deletes is not checked; the cached pairs still are
    with pytest.raises(ExperimentError, match=rf"{out / 'data' / 'options.json'}: the cached "
                       r"pairs were made with targets = 'release', not 'day2night'.*delete"):
        records.check(out, OURS, ("clean/mix5/0",), has_config)
    # a training option too
    with pytest.raises(ExperimentError, match="made with lr = 0.001, not 0.01"):
        records.check(out, {**RELEASE, "lr": 0.01}, (), has_config)


def test_without_config_json_an_unrecorded_unit_or_cache_is_refused(tmp_path):
    out = tmp_path / "run"
    (out / "units" / "clean" / "ours" / "all" / "model").mkdir(parents=True)
    with pytest.raises(ExperimentError, match=r"config.json is gone and this unit records no "
                       r"options.*restore config.json from table.json"):
        records.check(out, OURS, (), has_config=False)
    records.check(out, OURS, (), has_config=True)  # config.json vouches for it
    records.check(out, OURS, ("clean/ours/all",), has_config=False)  # deleted and retrained
    (out / "data" / "real").mkdir(parents=True)
    (out / "data" / "real" / "000.y.npy").write_bytes(b"")
    with pytest.raises(ExperimentError, match=r"data: RUN/config.json is gone and the cached "
                       r"pairs record no options"):
        records.check(out, OURS, ("clean/ours/all",), has_config=False)


def test_a_damaged_record_is_named(tmp_path):
    out = made(tmp_path)
    path = out / "units" / "clean" / "mix5" / "0" / "options.json"
    path.write_text("[1]")
    with pytest.raises(ValueError, match=rf"{path}: damaged options record"):
        records.check(out, RELEASE, (), True)


def test_folds_json_is_never_relabelled(tmp_path):
    class C:
        folds_file, folds_sha256 = None, None

    release_made = {"source": {"file": "/k.p", "lists": {}, "sha256": "ab" * 32}}
    with pytest.raises(ExperimentError, match=r"folds.json: made from the fold file /k.p, this "
                       "run has seeded folds"):
        prepare.check_folds_source(tmp_path / "folds.json", release_made, C)
    C.folds_file, C.folds_sha256 = "/k.p", "cd" * 32
    with pytest.raises(ExperimentError, match="made from the fold file"):
        prepare.check_folds_source(tmp_path / "folds.json", release_made, C)
    with pytest.raises(ExperimentError, match="made from seeded folds .--seed., this run has "
                       "--folds-file /k.p"):
        prepare.check_folds_source(tmp_path / "folds.json", {}, C)
    C.folds_sha256 = "ab" * 32
    prepare.check_folds_source(tmp_path / "folds.json", release_made, C)


def test_deleting_config_json_never_relabels_a_release_run(tmp_path):
    """The issue's reproducer: a --protocol release run, its config.json deleted, rerun with
    day2night's options and one more row: refused before anything is written."""
    need_torch()
    real, days = tiny_real_set(tmp_path / "real", 105)
    k = tmp_path / "k_fold_indices_saved.p"
    k.write_bytes(pickle.dumps(release_lists()))
    run = tmp_path / "run"
    experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5"],
               protocol="release", folds_file=k).prepare()
    unit = run / "units" / "clean" / "mix5" / "0" / "options.json"
    assert json.loads(unit.read_text())["options"]["protocol"] == "release"
    (run / "config.json").unlink()
    before = sorted(p.name for p in run.rglob("*"))
    with pytest.raises(ExperimentError, match=r"options.json: the unit was made with protocol "
                       "= 'release', not 'day2night'"):
        experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5", "mix10"],
                   targets="day2night").prepare()
    assert sorted(p.name for p in run.rglob("*")) == before
    # the same options as the records: resumed, config.json written again from them
    experiment(days, real, run, task="clean", epochs=1, width=4, rows=["mix5"],
               protocol="release", folds_file=k).prepare()
    assert json.loads((run / "config.json").read_text())["protocol"] == "release"
