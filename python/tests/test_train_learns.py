"""Proof that the night ISP learns (issue 35 item 5): a small UNet trained for a few dozen
steps on a small synthetic set ends well above the untrained network's validation score.

The set: ``fixtures/day.dng`` (512 x 512) synthesized at night (``synth_pairs``, local mode,
the clean task), the top 384 rows cut into 32 x 32 training patches (192), the bottom 128
rows validating (64 patches). UNet width 4, batch 16, Adam at lr 1e-2 (the ``mini``
preset's rate), one torch thread and deterministic algorithms, seed 0.

Measured here (2-core VM, load 2-6, torch 2.15 CPU; the same numbers every run): untrained
6.53 dB validation PSNR, after 5 epochs (60 steps) 23.66 dB at width 4 (27.6 dB at width 8),
a gain of 17.1 dB in about 10 s of training. The test asks for a gain of at least
MARGIN_DB = 10 dB, well under what was measured, so a
change in the last bits of the arithmetic cannot fail it, while a network that does not
learn (the untrained score, or a loss that does not reach the weights) cannot pass it."""

import numpy as np
import pytest

from conftest import FIXTURES, need_torch

MARGIN_DB = 10.0
EPOCHS = 5


@pytest.fixture()
def deterministic():
    torch = need_torch()
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    torch.use_deterministic_algorithms(True)
    yield torch
    torch.use_deterministic_algorithms(False)
    torch.set_num_threads(threads)


def small_set():
    from day2night.experiment.pairs import synth_pairs
    from day2night.train.data import FixedPatches

    x, y = synth_pairs(FIXTURES / "day.dng", "local", 0)["clean"]
    x, y = np.asarray(x), np.asarray(y)
    assert x.shape == (512, 512, 3)
    return (FixedPatches([x[:384]], [y[:384]], 32, 32),
            FixedPatches([x[384:]], [y[384:]], 32, 32))


def test_a_small_unet_learns_well_above_the_untrained_score(tmp_path, deterministic):
    from day2night.train import trainer

    train_set, val_set = small_set()
    cfg = trainer.TrainConfig(out_dir=str(tmp_path / "run"), epochs=EPOCHS, batch_size=16,
                              lr=1e-2, decay_at=1.0, init_features=4, seed=0, progress=False)
    out = trainer.train(cfg, train_set, val_set)
    start = out["initial"]["val_psnr"]
    end = max(h["val_psnr"] for h in out["history"])
    best = min(out["history"], key=lambda h: h["val_loss"])
    print(f"untrained {start:.2f} dB, best epoch {best['epoch']}: {best['val_psnr']:.2f} dB")
    assert start < 12, f"the untrained network already scores {start:.2f} dB"
    assert end - start >= MARGIN_DB, (
        f"validation PSNR {start:.2f} -> {end:.2f} dB: gained less than {MARGIN_DB} dB")
    assert out["history"][-1]["val_loss"] < 0.5 * out["initial"]["val_loss"]
    # the same numbers on a second run (fixed seed, one thread, deterministic algorithms)
    again = trainer.train(dataclass_copy(cfg, tmp_path / "again"), train_set, val_set)
    assert [h["val_loss"] for h in again["history"]] == [h["val_loss"] for h in out["history"]]


def dataclass_copy(cfg, out_dir):
    import dataclasses

    return dataclasses.replace(cfg, out_dir=str(out_dir))
