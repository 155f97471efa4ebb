"""NightPairs: deterministic items of (seed, epoch, index) in any process and order."""

import multiprocessing as mp
import pickle

import numpy as np
import pytest

import day2night
from day2night import NightPairs, pack_bayer


def items(ds, idx):
    return [ds[i] for i in idx]


def same(a, b):
    return all(
        np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k]
        for k in a
    )


def _worker(args):
    ds, idx = args
    return items(ds, idx)


def test_items_shapes_and_values(day_dir):
    ds = NightPairs(day_dir, crop=16, isos=(800, 3200), seed=5, crops_per_image=3)
    assert len(ds) == 6
    it = ds[0]
    assert it["noisy"].shape == (4, 8, 8) and it["noisy"].dtype == np.float32
    assert it["clean"].shape == (4, 8, 8)
    assert it["target"].shape == (3, 16, 16) and it["target"].dtype == np.float32
    assert it["iso"] in (800, 3200) and it["name"] == "a"
    assert np.isfinite(it["noisy"]).all() and np.isfinite(it["target"]).all()
    assert it["clean"].max() <= 1.0 + 1e-6
    # The item is synthesize() on its crop, packed.
    raw = day2night.read_dng(day_dir / "a.dng")
    top, left = it["origin"]
    p = ds.params(0)
    out = day2night.synthesize(raw, seed=5, variant=p["variant"], isos=(it["iso"],),
                               crop=(int(top), int(left), 16, 16))
    assert np.array_equal(day2night.pack_bayer(out["noisy"][it["iso"]], raw.meta, top, left),
                          it["noisy"])
    assert np.array_equal(out["target"].transpose(2, 0, 1), it["target"])
    y0, x0, ch, cw = raw.meta["default_crop"]
    assert top % 2 == 0 and left % 2 == 0
    assert y0 <= top <= y0 + ch - 16 and x0 <= left <= x0 + cw - 16


def test_deterministic_in_any_order_and_epochs_differ(day_dir):
    ds = NightPairs(day_dir, crop=16, seed=1, crops_per_image=2)
    fwd = items(ds, range(len(ds)))
    ds2 = NightPairs(day_dir, crop=16, seed=1, crops_per_image=2)
    back = items(ds2, reversed(range(len(ds2))))[::-1]
    assert all(same(a, b) for a, b in zip(fwd, back))
    ds.set_epoch(1)
    e1 = items(ds, range(len(ds)))
    assert not any(same(a, b) for a, b in zip(fwd, e1))
    ds.set_epoch(0)
    assert all(same(a, b) for a, b in zip(fwd, items(ds, range(len(ds)))))
    other_seed = NightPairs(day_dir, crop=16, seed=2, crops_per_image=2)
    assert not same(fwd[0], other_seed[0])


@pytest.mark.parametrize("method", ["spawn", "fork"])
def test_identical_in_worker_processes(day_dir, method):
    ds = NightPairs(day_dir, crop=16, seed=9, crops_per_image=2)
    ds.set_epoch(3)
    here = items(ds, range(len(ds)))  # also starts this process's worker threads before a fork
    ctx = mp.get_context(method)
    with ctx.Pool(2) as pool:
        parts = pool.map(_worker, [(ds, [0, 2]), (ds, [3, 1])], chunksize=1)
    there = {0: parts[0][0], 2: parts[0][1], 3: parts[1][0], 1: parts[1][1]}
    for i in range(len(ds)):
        assert same(here[i], there[i]), i
    pickle.loads(pickle.dumps(ds))


def test_errors(tmp_path, day_dir):
    with pytest.raises(ValueError, match="no .dng"):
        NightPairs(tmp_path)
    with pytest.raises(ValueError, match="not a folder"):
        NightPairs(tmp_path / "missing")
    with pytest.raises(ValueError, match="even"):
        NightPairs(day_dir, crop=15)
    ds = NightPairs(day_dir, crop=100000)
    with pytest.raises(ValueError, match="larger than"):
        ds[0]
    with pytest.raises(IndexError):
        NightPairs(day_dir, crop=16)[99]


def test_pack_bayer_by_hand():
    plane = np.array([[64, 1023], [544, 64]], dtype=np.uint16)
    meta = {"black_level": [64.0], "black_level_repeat_dim": (1, 1), "white_level": 1023.0}
    p = day2night.pack_bayer(plane, meta)
    assert p.shape == (4, 1, 1)
    assert np.allclose(p[:, 0, 0], [0.0, 1.0, 480 / 959, 0.0])
    with pytest.raises(ValueError):
        day2night.pack_bayer(np.zeros((3, 4), np.uint16), meta)


def test_items_equal_numpy_packing_with_a_black_level_pattern(tmp_path):
    # The Rust layout of an item (night_pair) equals pack_bayer of synthesize's arrays, here
    # on a BGGR raw with a 2x2 BlackLevel pattern (the black of each CFA position differs).
    import pathlib
    import shutil

    from day2night._native import night_pair

    fixtures = pathlib.Path(__file__).resolve().parents[2] / "fixtures"
    d = tmp_path / "d"
    d.mkdir()
    shutil.copy(fixtures / "bggr_14bit_packed_le_subifd_black2x2.dng", d / "p.dng")
    ds = NightPairs(d, crop=24, isos=(800, 3200), seed=2, crops_per_image=4)
    raw = day2night.read_dng(d / "p.dng")
    assert raw.meta["black_level_repeat_dim"] == (2, 2)
    assert len(set(raw.meta["black_level"])) > 1
    for i in range(len(ds)):
        it = ds[i]
        top, left = (int(x) for x in it["origin"])
        out = day2night.synthesize(raw, seed=2, variant=it["variant"], isos=(it["iso"],),
                                   crop=(top, left, 24, 24))
        assert np.array_equal(pack_bayer(out["noisy"][it["iso"]], raw.meta, top, left),
                              it["noisy"])
        assert np.array_equal(pack_bayer(out["clean"], raw.meta, top, left), it["clean"])
        assert np.array_equal(out["target"].transpose(2, 0, 1), it["target"])
        assert it["target"].flags.c_contiguous and it["noisy"].flags.c_contiguous
    with pytest.raises(ValueError, match="even"):
        night_pair(raw, 0, 0, 800, (0, 0, 15, 16))


def test_epoch_index_pairs_and_the_epoch_sampler(day_dir):
    """An (epoch, index) pair makes item index of that epoch whatever the dataset's own
    epoch; EpochSampler pairs a sampler's indices with the epoch current when iteration
    starts (what persistent DataLoader workers need)."""
    from day2night.pairs import EpochSampler
    ds = NightPairs(day_dir, crop=16, seed=3, crops_per_image=2)
    ds.set_epoch(7)
    want = [ds[i] for i in range(len(ds))]
    ds.set_epoch(0)
    assert all(same(w, ds[(7, i)]) for i, w in enumerate(want))
    assert not same(want[0], ds[0])
    sampler = EpochSampler([2, 0, 3], ds)
    ds.set_epoch(4)
    it = iter(sampler)
    ds.set_epoch(5)  # too late for the iteration already started
    assert list(it) == [(4, 2), (4, 0), (4, 3)] and len(sampler) == 3
    assert list(sampler) == [(5, 2), (5, 0), (5, 3)]
