"""NightPairs under torch.utils.data.distributed.DistributedSampler, without torch.

DistributedSampler hands rank r of R the indices ``perm[r:total:R]`` of a permutation of
``range(len(ds))`` (seeded by seed + epoch, padded by repeating its head to a multiple of
R, or cut with drop_last). ``distributed_indices`` reimplements that index logic as torch 2.x
documents and implements it (torch/utils/data/distributed.py), with numpy's permutation in
place of ``torch.randperm``: which permutation it is does not matter here, only how it is
split. NightPairs needs nothing from the sampler but indices: each rank (a process of its
own, with its own copy of the dataset) gets exactly the items a single process gets at the
same indices, because an item is a function of (seed, epoch, index) only."""

import math
import multiprocessing as mp
from collections import Counter

import numpy as np
import pytest

from day2night import NightPairs


def distributed_indices(n, num_replicas, rank, epoch=0, seed=0, shuffle=True, drop_last=False):
    """The indices DistributedSampler(dataset of length n, num_replicas, rank, shuffle,
    seed, drop_last) yields after set_epoch(epoch)."""
    if drop_last and n % num_replicas:
        num_samples = math.ceil((n - num_replicas) / num_replicas)
    else:
        num_samples = math.ceil(n / num_replicas)
    total = num_samples * num_replicas
    if shuffle:
        indices = np.random.default_rng(seed + epoch).permutation(n).tolist()
    else:
        indices = list(range(n))
    if not drop_last:
        pad = total - len(indices)
        if pad <= len(indices):
            indices += indices[:pad]
        else:
            indices += (indices * math.ceil(pad / len(indices)))[:pad]
    else:
        indices = indices[:total]
    assert len(indices) == total
    return indices[rank:total:num_replicas]


def same(a, b):
    return all(
        np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k]
        for k in a
    )


def _rank(args):
    """One rank: its own copy of the dataset (pickled into a spawned process), its epoch."""
    ds, epoch, indices = args
    ds.set_epoch(epoch)
    return [ds[i] for i in indices]


@pytest.mark.parametrize("n", [1, 5, 6, 7, 12])
@pytest.mark.parametrize("world", [1, 2, 3, 4])
@pytest.mark.parametrize("drop_last", [False, True])
def test_sampler_index_logic(n, world, drop_last):
    for epoch in range(3):
        parts = [distributed_indices(n, world, r, epoch, drop_last=drop_last)
                 for r in range(world)]
        assert len({len(p) for p in parts}) == 1  # every rank the same number of steps
        flat = [i for p in parts for i in p]
        assert all(0 <= i < n for i in flat)
        if drop_last or n % world == 0:
            assert len(set(flat)) == len(flat), "ranks share an index"
            if n % world == 0:
                assert sorted(flat) == list(range(n))
        else:
            # Without drop_last the sampler pads by repeating the permutation's head: every
            # index is served, and the only repeats are that padding.
            assert set(flat) == set(range(n))
            repeats = sum(c - 1 for c in Counter(flat).values())
            assert repeats == math.ceil(n / world) * world - n


def test_ranks_get_disjoint_items_that_depend_only_on_seed_epoch_index(day_dir):
    world = 2
    ds = NightPairs(day_dir, crop=16, isos=(800, 3200), seed=4, crops_per_image=3)
    n = len(ds)
    assert n % world == 0
    ctx = mp.get_context("spawn")
    with ctx.Pool(world) as pool:
        for epoch in (0, 1):
            parts = [distributed_indices(n, world, r, epoch, seed=4) for r in range(world)]
            assert not set(parts[0]) & set(parts[1])
            got = pool.map(_rank, [(ds, epoch, p) for p in parts], chunksize=1)
            ref = NightPairs(day_dir, crop=16, isos=(800, 3200), seed=4, crops_per_image=3)
            ref.set_epoch(epoch)
            for p, items in zip(parts, got):
                for i, item in zip(p, items):
                    assert same(item, ref[i]), (epoch, i)
            # Disjoint indices give different items across ranks (new crops and variants).
            for x in got[0]:
                assert not any(same(x, y) for y in got[1])
    # The same index in another world size and rank order: the same item.
    one = distributed_indices(n, 1, 0, 1, seed=4)
    ds.set_epoch(1)
    three = [i for r in range(3) for i in distributed_indices(n, 3, r, 1, seed=4)]
    assert sorted(one) == sorted(three)
    ref = NightPairs(day_dir, crop=16, isos=(800, 3200), seed=4, crops_per_image=3)
    ref.set_epoch(1)
    for i in three[:4]:
        assert same(ds[i], ref[i])
