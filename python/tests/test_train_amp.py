"""GPU options checked on CPU (issue 35 item 6): ``amp="bf16"`` (bfloat16 autocast) and
``channels_last`` give the float32 results within stated tolerances, in training
(``TrainConfig``) and in inference (``predict_float``).

Measured here (torch 2.15 CPU, one thread; UNet width 4, 4 epochs of 8 steps on a random
96 x 128 set), against float32 with the default memory format:

| | inference, same weights (max abs) | val L1 per epoch (max abs) | prediction after training (max abs) |
|---|---|---|---|
| channels_last | 6e-8 | 2.3e-6 | 7.9e-4 |
| bf16 | 2.3e-3 | 1.4e-4 | 7.8e-3 |

The tolerances below are about 10 times these (bf16 keeps 8 bits of mantissa: 2^-8 = 0.004
relative per operation); a bf16 path that is not autocast (float32) would pass too, so the
test also checks that bf16 changes the output at all."""

import dataclasses

import numpy as np
import pytest

from conftest import need_torch

TOL = {  # (inference same weights, val L1 per epoch, prediction after training)
    (None, True): (1e-6, 5e-5, 1e-2),
    ("bf16", False): (0.03, 2e-3, 0.08),
    ("bf16", True): (0.03, 2e-3, 0.08),
}


@pytest.fixture()
def one_thread():
    torch = need_torch()
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    yield torch
    torch.set_num_threads(n)


def sets():
    from day2night.train import data

    rng = np.random.default_rng(0)
    x = rng.random((96, 128, 3), dtype=np.float32)
    y = (np.clip(x ** 2 * 1.3, 0, 1) * 255).astype(np.uint8)
    return x, data.FixedPatches([x[:64]], [y[:64]], 32, 32), data.FixedPatches(
        [x[64:]], [y[64:]], 32, 32)


def run(tmp_path, amp, cl):
    from day2night.train import infer, trainer

    x, tr, va = sets()
    cfg = trainer.TrainConfig(out_dir=str(tmp_path / f"{amp}-{cl}"), epochs=4, batch_size=4,
                              lr=1e-2, init_features=4, progress=False, amp=amp,
                              channels_last=cl)
    out = trainer.train(cfg, tr, va)
    model = trainer.load_model(out["last"])
    return [h["val_loss"] for h in out["history"]], infer.predict_float(
        model, x, amp=amp, channels_last=cl)


@pytest.mark.parametrize("amp,cl", list(TOL))
def test_bf16_and_channels_last_match_float32(tmp_path, one_thread, amp, cl):
    from day2night.train import infer
    from day2night.train.unet import UNet

    torch = one_thread
    x = sets()[0]
    torch.manual_seed(0)
    model = UNet(3, 3, 4).eval()
    ref = infer.predict_float(model, x)
    got = infer.predict_float(model, x, amp=amp, channels_last=cl)
    tol_infer, tol_val, tol_pred = TOL[(amp, cl)]
    assert np.abs(got - ref).max() <= tol_infer
    if amp == "bf16":
        assert np.abs(got - ref).max() > 0, "bf16 autocast changed nothing"
    h0, p0 = run(tmp_path, None, False)
    h1, p1 = run(tmp_path, amp, cl)
    assert max(abs(a - b) for a, b in zip(h0, h1)) <= tol_val
    assert np.abs(p1 - p0).max() <= tol_pred


def test_bad_amp_is_refused(tmp_path):
    need_torch()
    from day2night.train import trainer

    cfg = trainer.TrainConfig(out_dir=str(tmp_path), amp="fp8")
    with pytest.raises(ValueError, match="amp 'fp8'"):
        cfg.check()
    assert dataclasses.replace(cfg, amp="bf16").check() is None
