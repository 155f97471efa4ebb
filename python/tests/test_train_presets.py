"""The experiment's training options (experiment/presets.py): --preset mini fills what the
command line leaves out, a flag wins over the preset, config.json holds only the options
that differ from the paper's (so earlier run folders resume), bad values are refused."""

import pytest

from day2night.experiment import __main__ as cli
from day2night.experiment import presets

BASE = ["--day", "d", "--real", "r", "-o", "o"]


def test_mini_preset_and_overrides():
    a = cli.parse(BASE + ["--preset", "mini"])
    assert (a.epochs, a.width, a.patch, a.batch, a.lr) == (40, 8, 32, 8, 1e-2)
    assert presets.config(a.train_opts) == {"patch": 32, "batch": 8, "lr": 1e-2,
                                            "preset": "mini"}
    a = cli.parse(BASE + ["--preset", "mini", "--epochs", "7", "--batch", "16"])
    assert (a.epochs, a.batch, a.width) == (7, 16, 8)


def test_paper_defaults_write_nothing_new():
    a = cli.parse(BASE)
    assert (a.epochs, a.width, a.patch, a.batch, a.lr) == (500, 32, 64, 128, 1e-3)
    assert presets.config(a.train_opts) == {}
    a = cli.parse(BASE + ["--amp", "bf16", "--channels-last", "--workers", "3"])
    assert presets.config(a.train_opts) == {"amp": "bf16", "channels_last": True}
    cfg = {}
    assert presets.apply(cfg, a.train_opts) == 3 and cfg["amp"] == "bf16"


@pytest.mark.parametrize("opts,msg", [({"patch": 40}, "--patch 40"), ({"batch": 0}, "--batch 0"),
                                      ({"lr": 0}, "--lr 0"), ({"workers": -1}, "--workers -1")])
def test_bad_values_are_refused(opts, msg):
    with pytest.raises(ValueError, match=msg):
        presets.config(opts)
