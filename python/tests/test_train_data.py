"""day2night.train.data: fixed patch sets (every 64x64 crop on the stride grid, indexed
lazily), fresh-synthesis patches, sharding; and the image noise estimate computed once per
raw (synthesize on an input without NoiseProfile)."""

import numpy as np
import pytest

import day2night
from conftest import need_torch


def pairs(rng, sizes):
    xs = [rng.random((h, w, 3), dtype=np.float32) for h, w in sizes]
    ys = [rng.integers(0, 256, (h, w, 3)).astype(np.uint8) for h, w in sizes]
    return xs, ys


def test_fixed_patches_cover_the_grid(tmp_path):
    need_torch()
    from day2night.train import data
    rng = np.random.default_rng(0)
    xs, ys = pairs(rng, [(130, 200), (64, 64), (63, 500)])
    ds = data.FixedPatches(xs, ys, patch=64, stride=64)
    # 2 x 3 + 1 + 0 (63 rows hold no patch)
    assert len(ds) == 7
    seen = []
    for i in range(len(ds)):
        k, top, left = ds.locate(i)
        x, y = ds[i]
        assert x.shape == (3, 64, 64) and y.shape == (3, 64, 64)
        assert np.array_equal(x.numpy(), xs[k][top:top + 64, left:left + 64].transpose(2, 0, 1))
        want = ys[k][top:top + 64, left:left + 64].transpose(2, 0, 1).astype(np.float32) / 255
        assert np.array_equal(y.numpy(), want)
        seen.append((k, top, left))
    assert seen == [(0, 0, 0), (0, 0, 64), (0, 0, 128), (0, 64, 0), (0, 64, 64), (0, 64, 128),
                    (1, 0, 0)]
    with pytest.raises(IndexError):
        ds[7]
    # stored as .npy and memory-mapped: the same items
    for n, (x, y) in enumerate(zip(xs, ys)):
        data.save_pair(tmp_path, f"im{n}", x, y)
    mm = data.FixedPatches.from_dir(tmp_path)
    assert isinstance(mm.inputs[0], np.memmap)
    assert len(mm) == 7 and all(np.array_equal(mm[i][0], ds[i][0]) for i in range(7))


def test_fixed_patches_refuse_bad_pairs():
    need_torch()
    from day2night.train import data
    x = np.zeros((64, 64, 3), np.float32)
    with pytest.raises(ValueError, match="uint8"):
        data.FixedPatches([x], [x])
    with pytest.raises(ValueError, match="same size"):
        data.FixedPatches([x], [np.zeros((64, 65, 3), np.uint8)])
    with pytest.raises(ValueError, match="no 64x64 patch"):
        data.FixedPatches([x[:10]], [np.zeros((10, 64, 3), np.uint8)])


def test_shards_are_disjoint_and_cover():
    torch = need_torch()
    from day2night.train import data
    rng = np.random.default_rng(0)
    ds = data.FixedPatches(*pairs(rng, [(256, 320)]))
    shards = [list(torch.utils.data.DistributedSampler(ds, 2, r, shuffle=True, seed=5))
              for r in (0, 1)]
    assert not set(shards[0]) & set(shards[1])
    assert sorted(shards[0] + shards[1]) == list(range(len(ds)))


def test_fresh_patches(day_dir):
    need_torch()
    from day2night.train import data, preprocess, targets
    ds = data.FreshPatches(day_dir, crop=128, patch=64, isos=(1600,), seed=2)
    assert len(ds) == 2 and ds.patches_per_item == 4
    x, y = ds[0]
    assert x.shape == (4, 3, 64, 64) and y.shape == (4, 3, 64, 64)
    assert x.dtype == y.dtype
    # the item is the release's input of the synthesized noisy crop, by the night neutral
    q = ds.pairs.place(0)
    out = day2night.synthesize(q["raw"], seed=2, variant=q["variant"], isos=(1600,),
                               crop=q["crop"])
    top, left = q["crop"][:2]
    xin = preprocess.network_input_array(out["noisy"][1600], q["raw"].meta, out["neutral"],
                                         top, left)
    assert np.array_equal(x[1].numpy(), xin[:64, 64:128].transpose(2, 0, 1))
    t8 = targets.srgb8(out["target"])
    assert np.array_equal(y[2].numpy(), t8[64:, :64].transpose(2, 0, 1).astype(np.float32) / 255)
    # deterministic; a new epoch draws new variants
    assert np.array_equal(ds[0][0].numpy(), x.numpy())
    ds.set_epoch(1)
    assert not np.array_equal(ds[0][0].numpy(), x.numpy())
    with pytest.raises(ValueError, match="multiple"):
        data.FreshPatches(day_dir, crop=100, patch=64)


@pytest.mark.parametrize("task,gamma", [("noisy", None), ("clean", 1 / 2.2), ("noisy", 0.5)])
def test_fresh_patches_native_path_equals_the_numpy_path(day_dir, task, gamma):
    """The one native call per item (fresh_pair) gives the bits of synthesize + the numpy
    network input (with its gamma table) + srgb8 + cut, for every item, task and gamma."""
    need_torch()
    from day2night.train import data
    ds = data.FreshPatches(day_dir, crop=192, patch=64, isos=(1600, 3200), seed=5,
                           crops_per_image=2, task=task, gamma=gamma)
    for epoch in (0, 3):
        ds.set_epoch(epoch)
        for i in range(len(ds)):
            xr, yr = ds.reference_arrays(i)
            x, y = ds.arrays(i)
            assert x.dtype == np.float32 and y.dtype == np.uint8
            assert np.array_equal(x, xr) and np.array_equal(y, yr), (epoch, i)
            xs, ys = ds[i]
            assert np.array_equal(xs.numpy(), data.cut(xr, 64))
            assert np.array_equal(ys.numpy(), data.cut(yr, 64).astype(np.float32) / np.float32(255))


def test_fresh_pair_arguments(day_dng):
    from day2night._native import fresh_pair
    raw = day2night.read_dng(day_dng)
    crop = (0, 0, 128, 128)
    x, y = fresh_pair(raw, crop, 1600, patch=32)
    assert x.shape == y.shape == (16, 3, 32, 32)
    # the default table: code / 16383 ** (1/2.2) by Rust's powf, within 1 ulp of numpy's
    from day2night.train import preprocess
    xt, _ = fresh_pair(raw, crop, 1600, table=preprocess._table(preprocess.GAMMA))
    xd, _ = fresh_pair(raw, crop, 1600)
    assert np.max(np.abs(xd.view(np.int32) - xt.view(np.int32))) <= 1
    with pytest.raises(ValueError, match="task"):
        fresh_pair(raw, crop, 1600, task="both")
    with pytest.raises(ValueError, match="whole number of 48x48"):
        fresh_pair(raw, crop, 1600, patch=48)
    with pytest.raises(ValueError, match="16384"):
        fresh_pair(raw, crop, 1600, table=np.zeros(10, dtype=np.float32))
    with pytest.raises(ValueError, match="odd|even"):
        fresh_pair(raw, (1, 0, 64, 64), 1600)


def test_fresh_pair_writes_its_patches_into_out(day_dng):
    """out=(x, y): the patches are written into the caller's arrays (returned as given),
    with the values of the arrays the call returns without it; wrong buffers are refused
    before anything is computed."""
    from day2night._native import fresh_pair
    raw = day2night.read_dng(day_dng)
    crop = (0, 0, 128, 128)
    x, y = fresh_pair(raw, crop, 1600, patch=32)
    bx = np.full((2 * 16, 3, 32, 32), np.nan, dtype=np.float32)
    by = np.full_like(bx, np.nan)
    gx, gy = fresh_pair(raw, crop, 1600, patch=32, out=(bx[16:], by[16:]))
    assert gx.base is bx and gy.base is by
    assert np.array_equal(bx[16:], x) and np.array_equal(by[16:], y)
    assert np.isnan(bx[:16]).all() and np.isnan(by[:16]).all()
    good = np.zeros_like(x)
    for bad, match in [
        ((np.zeros((15, 3, 32, 32), np.float32), good), "shape"),
        ((np.zeros_like(x, dtype=np.float64), good), "float32"),
        ((np.zeros((16, 3, 32, 64), np.float32)[..., ::2], good), "C-contiguous"),
        ((good, good), "writable"),
        ((good,), "pair"),
    ]:
        with pytest.raises(ValueError, match=match):
            fresh_pair(raw, crop, 1600, patch=32, out=bad)
    with pytest.raises(ValueError, match="patch"):
        fresh_pair(raw, crop, 1600, out=(good, np.zeros_like(x)))
    frozen = np.zeros_like(x)
    frozen.flags.writeable = False
    with pytest.raises(ValueError, match="writable"):
        fresh_pair(raw, crop, 1600, patch=32, out=(np.zeros_like(x), frozen))


def test_fresh_batches_are_made_in_place_with_the_items_values(day_dir):
    """FreshPatches.__getitems__ (what a DataLoader calls) writes a batch's items straight
    into one pair of tensors, in shared memory in a worker: the same values as collating
    the items one by one, with 0 and 1 workers."""
    need_torch()
    import torch
    from day2night.train import data
    ds = data.FreshPatches(day_dir, crop=128, patch=64, isos=(1600, 3200), seed=2,
                           crops_per_image=3)
    ds.set_epoch(1)
    want = [data.collate([ds[i] for i in range(k, min(k + 2, len(ds)))])
            for k in range(0, len(ds), 2)]
    batch = ds.__getitems__([0, 1])
    assert isinstance(batch, data.Batch) and not batch[0].is_shared()
    assert all(torch.equal(a, b) for a, b in zip(data.collate(batch), want[0]))
    for workers in (0, 1):
        loader = torch.utils.data.DataLoader(ds, batch_size=2, num_workers=workers,
                                             collate_fn=_collate_and_where)
        got = list(loader)
        assert len(got) == len(want)
        for (x, y, shared), (wx, wy) in zip(got, want):
            assert bool(shared.all()) == (workers == 1)
            assert torch.equal(x, wx) and torch.equal(y, wy)


def test_fresh_patches_take_the_cache_bounds_and_preload(day_dir):
    """FreshPatches passes ``cache``/``cache_bytes`` to its NightPairs (not to the synthesis,
    which refused them as unknown options), and ``preload`` decodes the images: the same
    items as without it."""
    need_torch()
    import torch
    from day2night.train import data
    ref = data.FreshPatches(day_dir, crop=128, patch=64, isos=(1600,), seed=4,
                            crops_per_image=2, cache=1)
    want = [ref[i] for i in range(len(ref))]
    assert ref.pairs.cached() == ["b.dng"]
    ds = data.FreshPatches(day_dir, crop=128, patch=64, isos=(1600,), seed=4,
                           crops_per_image=2, cache_bytes=1 << 40)
    assert ds.preload() == 2 and ds.pairs.cached() == ["a.dng", "b.dng"]
    for (x, y), (wx, wy) in zip((ds[i] for i in range(len(ds))), want):
        assert torch.equal(x, wx) and torch.equal(y, wy)


def test_noise_estimate_is_made_once_per_raw_with_the_same_numbers(day_dng):
    raw = day2night.read_dng(day_dng)
    meta = dict(raw.meta)
    meta["noise_profile"] = None
    assert meta["iso"]
    crops = [(0, 0, 64, 64), (64, 128, 64, 64), (0, 0, 64, 64)]
    kept = day2night.Raw.from_array(raw.data, meta, name=raw.name)
    repeated = [day2night.synthesize(kept, seed=1, isos=(1600,), crop=c) for c in crops]
    for c, out in zip(crops, repeated):
        fresh = day2night.Raw.from_array(raw.data, meta, name=raw.name)
        ref = day2night.synthesize(fresh, seed=1, isos=(1600,), crop=c)
        assert ref["noise_provenance"]["source"] == "image_estimate"
        assert ref["noise_profile"] == out["noise_profile"]
        assert np.array_equal(ref["noisy"][1600], out["noisy"][1600])


def test_fresh_pair_of_a_linearized_input_reads_the_linear_night_samples(day_dng):
    """The night raws of an input with a LinearizationTable hold linear samples (the table
    is applied once, by the synthesis, and dropped from their metadata): the network input
    normalizes them as they are. (The numpy path of earlier versions applied the day
    input's table a second time.)"""
    from day2night._native import fresh_pair
    from day2night.train import preprocess
    raw = day2night.read_dng(day_dng)
    meta = dict(raw.meta)
    # a curve that moves every value: x -> x * 7 / 8 + x^2 / 40000, capped at white
    x = np.arange(4096, dtype=np.float64)
    meta["linearization_table"] = list(np.minimum(x * 7 / 8 + x * x / 40000, 4095).astype(int))
    lin = day2night.Raw.from_array(raw.data, meta, name=raw.name)
    crop = (64, 96, 128, 128)
    out = day2night.synthesize(lin, seed=4, variant=2, isos=(3200,), crop=crop)
    night_meta = dict(meta, linearization_table=None)
    want = preprocess.network_input_array(out["noisy"][3200], night_meta, out["neutral"], 64, 96)
    got, y = fresh_pair(lin, crop, 3200, seed=4, variant=2,
                        table=preprocess._table(preprocess.GAMMA))
    assert np.array_equal(got, want)
    twice = preprocess.network_input_array(out["noisy"][3200], meta, out["neutral"], 64, 96)
    assert not np.array_equal(got, twice)
    from day2night.train import targets
    assert np.array_equal(y, targets.srgb8(out["target"]))


def _collate_and_where(batch):
    """The trainer's collate, and whether its batch was made in shared memory (run in a
    DataLoader worker)."""
    from day2night.train import data
    x, y = data.collate(batch)
    import torch
    return x, y, torch.tensor([x.is_shared(), y.is_shared()])


def test_a_workers_batch_is_made_in_shared_memory():
    """In a DataLoader worker the collated batch is written straight into shared memory (as
    torch's own default_collate does), not copied there afterwards; the values equal the
    in-process batch's."""
    need_torch()
    import torch
    from day2night.train import data
    rng = np.random.default_rng(3)
    xs, ys = pairs(rng, [(128, 192)])
    ds = data.FixedPatches(xs, ys, patch=64, stride=64)
    here = [data.collate([ds[i] for i in range(k, min(k + 4, len(ds)))])
            for k in range(0, len(ds), 4)]
    assert not here[0][0].is_shared()
    loader = torch.utils.data.DataLoader(ds, batch_size=4, num_workers=1,
                                         collate_fn=_collate_and_where)
    got = list(loader)
    assert len(got) == len(here)
    for (x, y, shared), (hx, hy) in zip(got, here):
        assert bool(shared.all()), "the worker's batch was not made in shared memory"
        assert torch.equal(x, hx) and torch.equal(y, hy)
