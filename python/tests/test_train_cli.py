"""``python -m day2night.train``'s flags are TrainConfig's fields: the same defaults, and a
parsed command line gives the TrainConfig it spells."""

import dataclasses

import pytest

from conftest import need_torch

need_torch(module=True)

from day2night.train import __main__ as cli  # noqa: E402
from day2night.train.trainer import TrainConfig  # noqa: E402

BASE = ["--train", "t", "--val", "v", "-o", "o"]


def test_the_parser_defaults_are_trainconfigs():
    args = cli.parser().parse_args(BASE)
    for f in dataclasses.fields(TrainConfig):
        if f.name != "out_dir":
            assert getattr(args, f.name) == f.default, f.name
    assert cli.config(args) == TrainConfig(out_dir="o")


def test_flags_set_the_fields():
    args = cli.parser().parse_args(BASE + [
        "--epochs", "7", "--batch-size", "16", "--lr", "0.01", "--decay-at", "0.5",
        "--decay", "0.5", "--init-features", "8", "--seed", "3", "--device", "cuda",
        "--workers", "2", "--no-progress", "--record-shards", "--amp", "bf16",
        "--channels-last"])
    assert cli.config(args) == TrainConfig(
        out_dir="o", epochs=7, batch_size=16, lr=0.01, decay_at=0.5, decay=0.5,
        init_features=8, seed=3, device="cuda", workers=2, progress=False, record_shards=True,
        amp="bf16", channels_last=True)
    assert (args.patch, args.crop, args.crops_per_image, args.task) == (64, 512, 1, "noisy")
