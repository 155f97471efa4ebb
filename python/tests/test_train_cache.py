"""The compact input store (issue 35 item 7; day2night.train.cache): 14-bit CFA codes and a
border ring instead of float32 H x W x 3, read back bit for bit, in the experiment's cache
(pairs.cached / load), in save_pair / FixedPatches, for every orientation and crop that
align can give; an old float32 cache is migrated, a damaged or unknown one refused."""

import numpy as np
import pytest

from conftest import FIXTURES, need_torch

import day2night
from day2night.experiment import pairs
from day2night.train import cache, preprocess


@pytest.fixture(scope="module")
def x_full():
    return preprocess.network_input(day2night.read_dng(str(FIXTURES / "day.dng")))


def bits(a):
    return np.ascontiguousarray(a, np.float32).view(np.uint32)


@pytest.mark.parametrize("orientation", range(1, 9))
@pytest.mark.parametrize("crop", [None, (3, 5, 250, 245), (2, 0, 128, 97)])
def test_decoded_input_is_bit_identical(x_full, orientation, crop):
    x = x_full if crop is None else x_full[crop[0]:crop[0] + crop[2], crop[1]:crop[1] + crop[3]]
    x = np.ascontiguousarray(pairs.orient(x, orientation))
    a = cache.encode(x)
    h, w = x.shape[:2]
    assert cache.info(a)["encoding"] == cache.CFA14
    # 2 B/px + the two rings (12 codes per border pixel) + a 32-byte header: at most 4 B/px
    assert cache.nbytes_per_pixel(a) <= 2 + 24 * (h + w) / (h * w) + 32 / (h * w) + 1e-9 <= 4
    assert np.array_equal(bits(cache.decode(a)), bits(x))
    for top in range(0, h - 31, 29):  # windows at every phase and on the rings
        for left in range(0, w - 31, 31):
            got = cache.decode_window(a, top, left, 32, 32)
            assert np.array_equal(bits(got), bits(x[top:top + 32, left:left + 32])), (top, left)


def test_other_inputs_fall_back_to_exact_stores(x_full):
    lin = preprocess.network_input_array(
        np.asarray(day2night.read_dng(str(FIXTURES / "day.dng")).data)[:64, :64],
        day2night.read_dng(str(FIXTURES / "day.dng")).meta, gamma=None)
    a = cache.encode(lin)
    assert cache.info(a)["gamma"] is None and np.array_equal(bits(cache.decode(a)), bits(lin))
    noise = np.random.default_rng(0).random((20, 30, 3), dtype=np.float32)
    b = cache.encode(noise)
    assert cache.info(b)["encoding"] == cache.FLOAT32
    assert np.array_equal(bits(cache.decode(b)), bits(noise))
    tiny = np.ascontiguousarray(x_full[:4, :5])
    c = cache.encode(tiny)
    assert cache.info(c)["encoding"] == cache.RGB14
    assert np.array_equal(bits(cache.decode(c)), bits(tiny))


def test_experiment_cache_stores_about_2_bytes_per_pixel_and_migrates(tmp_path, x_full):
    y = np.zeros(x_full.shape, np.uint8)
    paths = pairs.cached(tmp_path, {"k": "img"}, lambda: {"k": (x_full, y)})
    xp, yp = paths["k"]
    assert xp.name == "img.in.npy"
    assert np.array_equal(bits(pairs.load(xp)), bits(x_full))
    assert pairs.check_cached(xp, yp) == (512, 512)
    assert xp.stat().st_size / (512 * 512) < 2.2  # against 12 B/px of float32 x 3
    # a run folder of the first format: <name>.x.npy float32, migrated on first use
    old = tmp_path / "old"
    old.mkdir()
    np.save(old / "img.x.npy", x_full)
    np.save(old / "img.y.npy", y)
    paths = pairs.cached(old, {"k": "img"}, lambda: pytest.fail("must not remake the pair"))
    assert not (old / "img.x.npy").exists()
    assert np.array_equal(bits(pairs.load(paths["k"][0])), bits(x_full))


def test_damaged_and_unknown_stores_are_refused(tmp_path, x_full):
    a = cache.encode(x_full)
    with pytest.raises(cache.CacheFormatError, match="truncated"):
        cache.info(a[:-5], "img.in.npy")
    b = a.copy()
    b[2] = 99
    with pytest.raises(cache.CacheFormatError, match="version 99"):
        cache.decode(b, "img.in.npy")
    np.save(tmp_path / "img.in.npy", b)
    np.save(tmp_path / "img.y.npy", np.zeros(x_full.shape, np.uint8))
    with pytest.raises(ValueError, match="img.in.npy"):
        pairs.check_cached(tmp_path / "img.in.npy", tmp_path / "img.y.npy")


def test_save_pair_and_fixed_patches_read_the_store(tmp_path, x_full):
    need_torch()  # FixedPatches is a torch Dataset
    from day2night.train import data

    y = (np.arange(x_full.size) % 251).astype(np.uint8).reshape(x_full.shape)
    x = np.ascontiguousarray(x_full[:200, :300])
    data.save_pair(tmp_path, "a", x, y[:200, :300])
    assert np.load(tmp_path / "a_x.npy").dtype == np.uint16
    stored = data.FixedPatches.from_dir(tmp_path, 64, 64)
    plain = data.FixedPatches([x], [y[:200, :300]], 64, 64)
    assert len(stored) == len(plain) == 3 * 4
    for i in range(len(plain)):
        for s, p in zip(stored[i], plain[i]):
            assert torch_equal(s, p)


def torch_equal(a, b):
    return np.array_equal(a.numpy().view(np.uint32), b.numpy().view(np.uint32))
