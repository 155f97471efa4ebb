"""day2night.train.infer and .scores: tiled inference gives the untiled bytes; the scores
are scikit-image's (the release's test.py conventions) and `day2night eval`'s."""

import json
import os

import numpy as np
import pytest

import day2night
from day2night.train import scores
from conftest import need_torch


def model(f=4, seed=0):
    torch = need_torch()
    from day2night.train.unet import UNet
    torch.manual_seed(seed)
    m = UNet(3, 3, f)
    # non-trivial BatchNorm statistics, as after training
    with torch.no_grad():
        for mod in m.modules():
            if isinstance(mod, torch.nn.BatchNorm2d):
                mod.running_mean.uniform_(-0.2, 0.2)
                mod.running_var.uniform_(0.5, 2.0)
    return m.eval()


def test_tiled_equals_untiled_and_padding():
    need_torch()
    from day2night.train import infer
    m = model()
    rng = np.random.default_rng(0)
    # not multiples of 16; taller than a tile and its two 112-pixel halos, so tiles see
    # only part of the image
    x = rng.random((410, 90, 3), dtype=np.float32)
    whole = infer.predict(m, x, tile=None)
    assert whole.dtype == np.uint8 and whole.shape == (410, 90, 3)
    for tile in (64, 128):  # 7 x 2 tiles; 4 x 1 tiles
        assert np.array_equal(infer.predict(m, x, tile=tile), whole), tile
    assert np.array_equal(infer.predict(m, x), whole)  # "auto": whole at this size
    f = infer.predict_float(m, x, tile=None)
    assert np.array_equal(whole, (255 * np.clip(f, 0, 1)).astype(np.uint8))
    with pytest.raises(ValueError, match="multiple of 16"):
        infer.predict(m, x, tile=100)


def test_png_written(tmp_path):
    from day2night.train import infer
    skio = pytest.importorskip("skimage.io")
    a = np.random.default_rng(1).integers(0, 256, (17, 23, 3)).astype(np.uint8)
    infer.write_png(tmp_path / "p.png", a)
    assert np.array_equal(skio.imread(tmp_path / "p.png"), a)
    assert os.listdir(tmp_path) == ["p.png"]


def images():
    rng = np.random.default_rng(2)
    t = rng.integers(0, 256, (48, 40, 3)).astype(np.uint8)
    p = np.clip(t.astype(int) + rng.integers(-9, 10, t.shape), 0, 255).astype(np.uint8)
    return p, t


def test_scores_equal_scikit_image():
    metrics = pytest.importorskip("skimage.metrics")
    p, t = images()
    s = scores.score(p, t)
    # day2night computes in float32 (as `day2night eval` reads a PNG), scikit-image in float64
    assert s["psnr"] == pytest.approx(metrics.peak_signal_noise_ratio(t, p, data_range=255),
                                      abs=1e-6)
    assert s["ssim"] == pytest.approx(
        metrics.structural_similarity(t, p, channel_axis=-1, data_range=255), abs=1e-6)
    color = pytest.importorskip("skimage.color")
    de = color.deltaE_ciede2000(color.rgb2lab(t), color.rgb2lab(p)).mean()
    assert s["delta_e"] == pytest.approx(de, rel=1e-4, abs=1e-4)
    both = scores.score_set([("a", p, t), ("b", t, t)])
    assert [r["name"] for r in both["images"]] == ["a", "b"]
    assert both["mean"]["ssim"] == pytest.approx((s["ssim"] + 1.0) / 2)


def test_scores_equal_day2night_eval(tmp_path, cli):
    from day2night.train import infer
    p, t = images()
    infer.write_png(tmp_path / "p.png", p)
    infer.write_png(tmp_path / "t.png", t)
    got = json.loads(cli("eval", tmp_path / "p.png", tmp_path / "t.png", "--json").stdout)
    if isinstance(got, list):
        got = got[0]
    s = scores.score(p, t)
    assert s["psnr"] == pytest.approx(got["psnr"], abs=1e-9)
    assert s["ssim"] == pytest.approx(got["ssim"], abs=1e-9)
    assert s["delta_e"] == pytest.approx(got["delta_e_2000"], abs=1e-9)
    # and day2night's own functions on the 8-bit images
    pf, tf = p.astype(np.float32) / np.float32(255), t.astype(np.float32) / np.float32(255)
    assert s["psnr"] == pytest.approx(day2night.psnr(pf, tf), abs=1e-9)
    assert s["ssim"] == pytest.approx(day2night.ssim(pf, tf), abs=1e-9)
    assert s["delta_e"] == pytest.approx(
        day2night.delta_e2000(pf, tf, pred_linear=False, target_linear=False), abs=1e-9)


def test_scores_refuse_bad_images():
    p, t = images()
    with pytest.raises(ValueError, match="uint8"):
        scores.score(p.astype(np.float32), t)
    with pytest.raises(ValueError, match="differ"):
        scores.score(p[:10], t)
