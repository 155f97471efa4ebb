"""Crop-aware synthesis: the crop's clean raw and target equal the whole frame's region;
its noise has the model's statistics."""

import numpy as np
import pytest

import day2night


@pytest.fixture(scope="module")
def raw(real_dng):
    return day2night.read_dng(real_dng)


@pytest.fixture(scope="module")
def full(raw):
    return day2night.synthesize(raw, seed=11, variant=2, isos=(3200,))


def active_region(raw, plane, top, left, h, w):
    t, l, _, _ = raw.meta["active_area"]
    return plane[t + top:t + top + h, l + left:l + left + w]


@pytest.mark.parametrize("crop", [(0, 0, 64, 96), (40, 100, 128, 64), (2, 2, 33, 17)])
def test_crop_equals_whole_frame_region(raw, full, crop):
    top, left, h, w = crop
    res = day2night.synthesize(raw, seed=11, variant=2, isos=(3200,), crop=crop)
    assert res["clean"].shape == (h, w)
    assert np.array_equal(res["clean"], active_region(raw, full["clean"], top, left, h, w))
    assert res["plan"] == full["plan"]
    assert res["neutral"] == full["neutral"]
    origin = res["target_origin"]
    y0, x0, ch, cw = raw.meta["default_crop"]
    if top >= y0 and left >= x0 and top + h <= y0 + ch and left + w <= x0 + cw:
        assert origin == (top - y0, left - x0)
        oy, ox = origin
        region = full["target"][oy:oy + h, ox:ox + w]
        assert res["target"].shape == (h, w, 3)
        assert np.abs(res["target"] - region).max() <= 1e-3
    else:
        assert origin is None
    assert res["noisy"][3200].shape == (h, w)
    assert "crop" in res["stages"]


def test_crop_noise_has_the_declared_statistics(raw):
    crop = (0, 0, 256, 256)
    res = day2night.synthesize(raw, seed=4, isos=(6400,), crop=crop, mode="dimmed")
    again = day2night.synthesize(raw, seed=4, isos=(6400,), crop=crop, mode="dimmed")
    assert np.array_equal(res["noisy"][6400], again["noisy"][6400])
    clean = res["clean"].astype(np.float64)
    noisy = res["noisy"][6400].astype(np.float64)
    black = float(max(raw.meta["black_level"]))
    white = float(raw.meta["white_level"])
    scale = white - black
    prof = res["noise_profile"][6400]  # [[S, O]] per colour plane (R, G, B)
    cfa = raw.meta["cfa_pattern"]
    z_all = []
    for i in range(2):
        for j in range(2):
            colour = "RGB".index(cfa[2 * i + j])
            s, o = prof[colour]
            x = clean[i::2, j::2]
            y = (x - black) / scale
            var = np.maximum(s * y + o, 0) * scale * scale
            n = noisy[i::2, j::2]
            ok = (var > 1) & (n > 0) & (n < white) & (x > black)
            z_all.append(((n - x)[ok]) / np.sqrt(var[ok]))
    z = np.concatenate(z_all)
    assert z.size > 10000
    assert abs(z.mean()) < 0.05, z.mean()
    assert abs(z.var() - 1) < 0.08, z.var()
    # another crop draws another stream
    other = day2night.synthesize(raw, seed=4, isos=(6400,), crop=(2, 0, 256, 256), mode="dimmed")
    assert not np.array_equal(other["noisy"][6400][:-2], res["noisy"][6400][2:])


def test_crop_computes_only_what_is_asked(raw):
    res = day2night.synthesize(raw, seed=1, isos=(), target=None, crop=(0, 0, 32, 32))
    assert res["target"] is None and res["noisy"] == {}
    assert "render_target" not in res["stages"]


def test_write_outputs_refuses_a_crop(raw, tmp_path):
    res = day2night.synthesize(raw, seed=1, isos=(1600,), crop=(0, 0, 32, 32))
    with pytest.raises(ValueError, match="crop"):
        day2night.write_outputs(res, raw, tmp_path)
