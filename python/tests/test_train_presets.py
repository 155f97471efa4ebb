"""The experiment's options (experiment/config.py, presets.py): the command line is made from
ExperimentConfig's fields (the same defaults), --preset mini fills what the command line
leaves out, a flag wins over the preset, config.json holds only the training options that
differ from the paper's (so earlier run folders resume), bad values are refused."""

import dataclasses

import pytest

from day2night.experiment import __main__ as cli
from day2night.experiment import config

BASE = ["--day", "d", "--real", "r", "-o", "o"]
TRAIN = {"patch", "batch", "lr", "amp", "channels_last", "preset"}


def training(c):
    """The training options of a config's record (config.json)."""
    return {k: v for k, v in c.record().items() if k in TRAIN}


def test_the_parser_defaults_are_the_fields():
    args = cli.parser().parse_args(BASE)
    for f in dataclasses.fields(config.ExperimentConfig):
        if f.name in ("day", "real", "output"):
            assert getattr(args, f.name) == {"day": "d", "real": "r", "output": "o"}[f.name]
        elif config.flags_of(f):
            want = list(f.default) if isinstance(f.default, tuple) else f.default
            assert getattr(args, f.name) == want, f.name
        else:
            assert not hasattr(args, f.name)


def test_the_recorded_keys_are_the_compared_ones():
    recorded = {f.name for f in dataclasses.fields(config.ExperimentConfig)
                if f.metadata["record"] in ("always", "paper")}
    assert set(config.CONFIG_KEYS) == recorded and len(config.CONFIG_KEYS) == len(recorded)
    # the order a resume names the first difference in, as before the keys came from the
    # fields
    assert config.CONFIG_KEYS == (
        "day", "real", "task", "epochs", "seed", "seeds", "folds", "width", "device", "rows",
        "protocol", "targets", "noise", "synth_iso", "folds_file", "folds_sha256",
        "patch", "batch", "lr", "amp", "channels_last")
    assert config.PAPER_VALUES == {"patch": 64, "batch": 128, "lr": 1e-3, "amp": None,
                                   "channels_last": False, "seeds": 1}


def test_mini_preset_and_overrides():
    a = cli.parse(BASE + ["--preset", "mini"])
    assert (a.epochs, a.width, a.patch, a.batch, a.lr) == (40, 8, 32, 8, 1e-2)
    assert training(a) == {"patch": 32, "batch": 8, "lr": 1e-2, "preset": "mini"}
    a = cli.parse(BASE + ["--preset", "mini", "--epochs", "7", "--batch", "16"])
    assert (a.epochs, a.batch, a.width) == (7, 16, 8)


def test_paper_defaults_write_nothing_new():
    a = cli.parse(BASE)
    assert (a.epochs, a.width, a.patch, a.batch, a.lr) == (500, 32, 64, 128, 1e-3)
    assert training(a) == {}
    assert set(a.record()) == set(config.CONFIG_KEYS) - {"patch", "batch", "lr", "amp",
                                                         "channels_last", "seeds"}
    a = cli.parse(BASE + ["--amp", "bf16", "--channels-last", "--workers", "3"])
    assert training(a) == {"amp": "bf16", "channels_last": True}
    assert a.workers == 3 and "workers" not in a.record()


@pytest.mark.parametrize("opts,msg", [({"patch": 40}, "--patch 40"), ({"batch": 0}, "--batch 0"),
                                      ({"lr": 0}, "--lr 0"), ({"workers": -1}, "--workers -1"),
                                      ({"epochs": 0}, "--epochs 0"), ({"width": 0}, "--width 0"),
                                      ({"seed": -1}, "--seed -1"), ({"show": -1}, "--show -1"),
                                      ({"device": "tpu"}, "--device 'tpu'"),
                                      ({"targets": "srgb"}, "--targets 'srgb'"),
                                      ({"protocol": "release"}, "--protocol release needs"),
                                      ({"rows": ["nope"]}, "unknown row 'nope'")])
def test_bad_values_are_refused(opts, msg):
    c = dataclasses.replace(cli.parse(BASE), **opts)
    with pytest.raises(ValueError, match=msg):
        c.check()


def test_defaults_come_from_the_fields_sources_in_order():
    base = config.ExperimentConfig(day="d", real="r", output="o")
    # the preset alone: the training options; the others wait for their sources
    a = base.with_preset()
    assert (a.epochs, a.width, a.patch, a.batch, a.lr) == (500, 32, 64, 128, 1e-3)
    assert (a.targets, a.noise, a.synth_iso, a.folds) == (None, None, None, None)
    srcs = {"protocol": {"noise": "n"}, "real set": {"targets": "t"}, "fold file": {}}
    b = a.with_defaults(srcs)
    assert (b.targets, b.noise, b.synth_iso, b.folds) == ("t", "n", None, 3)
    # the first source with a value wins; a value given wins over every source
    c = a.with_defaults(dict(srcs, protocol={"targets": "p", "synth_iso": "s"},
                             **{"fold file": {"folds": 5}}))
    assert (c.targets, c.synth_iso, c.folds) == ("p", "s", 5)
    d = dataclasses.replace(a, targets="given").with_defaults(srcs)
    assert d.targets == "given"
    # every field with a default from a source names known sources or values
    for f in dataclasses.fields(config.ExperimentConfig):
        for src in f.metadata["default_from"]:
            assert src in config.SOURCES or not isinstance(src, str), (f.name, src)
