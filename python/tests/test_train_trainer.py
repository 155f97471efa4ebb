"""day2night.train.trainer: the loss falls, a seed gives the same weights, a killed run
resumes to the weights of an uninterrupted one, and torchrun runs 2 gloo ranks (DDP) on
disjoint shards with one checkpoint writer. Tiny width (init_features=4), few patches."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import need_torch


@pytest.fixture()
def sets(tmp_path):
    """Fixed pairs whose target is a smooth function of the input (learnable)."""
    need_torch()
    from day2night.train import data
    rng = np.random.default_rng(0)
    for split, n in (("train", 3), ("val", 1)):
        for k in range(n):
            x = rng.random((128, 128, 3), dtype=np.float32)
            y = (255 * x[..., ::-1] ** 2).astype(np.uint8)
            data.save_pair(tmp_path / split, f"{split}{k}", x, y)
    return tmp_path / "train", tmp_path / "val"


def config(out, **kw):
    from day2night.train.trainer import TrainConfig
    base = dict(out_dir=str(out), epochs=4, batch_size=8, init_features=4, seed=7,
                progress=False)
    base.update(kw)
    return TrainConfig(**base)


def run(cfg, sets):
    from day2night.train import data, trainer
    return trainer.train(cfg, data.FixedPatches.from_dir(sets[0]),
                         data.FixedPatches.from_dir(sets[1]))


def weights(path):
    from day2night.train.trainer import load_checkpoint
    return load_checkpoint(path)["model"]


def same_weights(a, b):
    wa, wb = weights(a), weights(b)
    return wa.keys() == wb.keys() and all(bool((wa[k] == wb[k]).all()) for k in wa)


def scores(history):
    return [{k: v for k, v in h.items() if k != "seconds"} for h in history]


def test_loss_falls_and_seed_repeats(tmp_path, sets):
    a = run(config(tmp_path / "a"), sets)
    b = run(config(tmp_path / "b"), sets)
    h = a["history"]
    assert len(h) == 4 and h[-1]["loss"] < h[0]["loss"]
    assert h[-1]["val_loss"] < h[0]["val_loss"]
    # lr x0.1 from 80 % of the epochs (epoch index 3 of 4)
    assert [r["lr"] for r in h] == pytest.approx([1e-3, 1e-3, 1e-3, 1e-4])
    assert scores(h) == scores(b["history"])
    assert same_weights(a["last"], b["last"]) and same_weights(a["best"], b["best"])
    best = min(range(4), key=lambda i: h[i]["val_loss"])
    from day2night.train.trainer import load_checkpoint
    assert load_checkpoint(a["best"])["epoch"] == best
    c = run(config(tmp_path / "c", seed=8), sets)
    assert not same_weights(a["last"], c["last"])


KILL_AT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "kill_at.py")


def cli(args, env=None, kill_at=None):
    """``python -m day2night.train ARGS``; ``kill_at=(E, S)``: SIGKILLed before step S of
    epoch E (kill_at.py's on_step callback)."""
    e = dict(os.environ, **(env or {}))
    head = ["-m"] if kill_at is None else [KILL_AT, "1", *map(str, kill_at)]
    return subprocess.run([sys.executable, *head, "day2night.train", *map(str, args)],
                          capture_output=True, text=True, env=e, timeout=300)


def test_killed_run_resumes_to_the_same_weights(tmp_path, sets):
    common = ["--train", sets[0], "--val", sets[1], "--epochs", 4, "--batch-size", 8,
              "--init-features", 4, "--seed", 3]
    whole = cli(common + ["-o", tmp_path / "whole", "--no-progress"])
    assert whole.returncode == 0, whole.stderr
    # SIGKILL at the second step of epoch 2 (0-based): epochs 0 and 1 are checkpointed
    killed = cli(common + ["-o", tmp_path / "cut"], kill_at=(2, 1))
    assert killed.returncode == -9, killed.stderr
    from day2night.train.trainer import load_checkpoint
    assert load_checkpoint(tmp_path / "cut" / "last.pt")["epoch"] == 1
    assert "val PSNR" in killed.stderr  # the progress line
    resumed = cli(common + ["-o", tmp_path / "cut", "--no-progress"])
    assert resumed.returncode == 0, resumed.stderr
    for name in ("last.pt", "best.pt"):
        assert same_weights(tmp_path / "whole" / name, tmp_path / "cut" / name), name
    hw = json.loads((tmp_path / "whole" / "history.json").read_text())
    hc = json.loads((tmp_path / "cut" / "history.json").read_text())
    assert scores(hw) == scores(hc)


def test_torchrun_two_gloo_ranks(tmp_path, sets):
    need_torch()
    out = tmp_path / "ddp"
    r = subprocess.run(
        [str(a) for a in [sys.executable, "-m", "torch.distributed.run", "--nproc-per-node", "2",
         "--master-port", str(29500 + os.getpid() % 1000),
         "-m", "day2night.train", "--train", sets[0], "--val", sets[1], "-o", out,
         "--epochs", 3, "--batch-size", 8, "--init-features", 4, "--no-progress",
         "--record-shards"]],
        capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-4000:]
    from day2night.train.trainer import load_checkpoint
    n = 3 * 4  # 3 images of 2 x 2 patches
    for e in range(3):
        s0 = json.loads((out / "shards" / f"rank0_epoch{e}.json").read_text())
        s1 = json.loads((out / "shards" / f"rank1_epoch{e}.json").read_text())
        assert not set(s0) & set(s1) and sorted(s0 + s1) == list(range(n))
    ck = load_checkpoint(out / "last.pt")
    assert (ck["writer_rank"], ck["world_size"], ck["epoch"]) == (0, 2, 2)
    assert sorted(p.name for p in out.iterdir()) == ["best.pt", "history.json", "last.pt",
                                                     "shards"]
    h = ck["history"]
    assert h[-1]["loss"] < h[0]["loss"]
    assert r.stdout.count("trained 3 epochs") == 1  # rank 0 reports


def test_bad_config_is_refused(tmp_path, sets):
    with pytest.raises(ValueError, match="epochs"):
        run(config(tmp_path / "x", epochs=0), sets)
    run(config(tmp_path / "r", epochs=1), sets)
    with pytest.raises(ValueError, match=r"last\.pt.*init_features 4 -> 8"):
        run(config(tmp_path / "r", epochs=1, init_features=8), sets)
    r = cli(["--train", tmp_path / "nowhere", "--val", sets[1], "-o", tmp_path / "y"])
    assert r.returncode == 2 and "nowhere" in r.stderr


def test_fresh_synthesis_source(tmp_path, sets, day_dir):
    """The trainer on FreshPatches: items of 4 patches, new variants every epoch."""
    from day2night.train import data, trainer
    fresh = data.FreshPatches(day_dir, crop=128, patch=64, isos=(1600,), seed=1)
    seen = []

    class Spy(type(fresh)):
        # every item goes through _pair, whether the loader asks for a batch of items
        # (__getitems__, the DataLoader's way) or for one (__getitem__)
        def _pair(self, i, patch, out=None):
            seen.append((self.epoch, i))
            return super()._pair(i, patch, out)

    fresh.__class__ = Spy
    out = trainer.train(config(tmp_path / "f", epochs=2), fresh,
                        data.FixedPatches.from_dir(sets[1]))
    assert len(out["history"]) == 2 and all(np.isfinite(h["loss"]) for h in out["history"])
    # 2 items of 4 patches per epoch (one batch of 8 patches), each epoch its own draws
    assert sorted(seen) == [(0, 0), (0, 1), (1, 0), (1, 1)]
