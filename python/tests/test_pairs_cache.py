"""The decoded day images that NightPairs (and FreshPatches through it) keep per process
(issue 48): bounded by a count (``cache``) and by the bytes of their planes
(``cache_bytes``), least recently used out first; ``preload()`` decodes them up front within
the same bounds, and the items are the same with or without it, here or in a forked worker
process."""

import multiprocessing as mp
import pickle
import shutil

import numpy as np
import pytest

import day2night
from day2night import NightPairs
from day2night.image_cache import CACHE_BYTES


@pytest.fixture
def three(tmp_path, day_dng):
    d = tmp_path / "days"
    d.mkdir()
    for name in ("a", "b", "c"):
        shutil.copy(day_dng, d / f"{name}.dng")
    return d


@pytest.fixture
def plane(day_dng):
    """Bytes of the fixture's decoded plane, from its array."""
    return day2night.read_dng(str(day_dng)).data.nbytes


def same(a, b):
    return all(
        np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k]
        for k in a
    )


#: The dataset a forked worker finds in its parent's memory (as DataLoader workers do).
PARENT = None


def _items_of_parent(idx):
    return PARENT.cached(), [PARENT[i] for i in idx]


def test_by_default_every_image_is_kept(three):
    assert CACHE_BYTES == 4 << 30
    ds = NightPairs(three, crop=16, crops_per_image=2)
    for i in (5, 0, 3, 1):
        ds[i]
    assert ds.cached() == ["c.dng", "b.dng", "a.dng"]  # least recently used first


def test_the_count_bound_drops_the_least_recently_used(three):
    ds = NightPairs(three, crop=16, crops_per_image=2, cache=2)
    for i in (0, 2, 1, 4):  # a, b, a again, c: b is the least recently used
        ds[i]
    assert ds.cached() == ["a.dng", "c.dng"]


def test_the_byte_bound_counts_the_planes(three, plane):
    ds = NightPairs(three, crop=16, crops_per_image=2, cache_bytes=2 * plane)
    for i in (0, 2, 4):
        ds[i]
    assert ds.cached() == ["b.dng", "c.dng"]
    # a bound below one plane still keeps the image in use
    one = NightPairs(three, crop=16, crops_per_image=2, cache_bytes=0)
    one[0]
    assert one.cached() == ["a.dng"]
    one[3]
    assert one.cached() == ["b.dng"]


def test_preload_stays_within_the_bounds(three, plane):
    assert NightPairs(three, crop=16).preload() == 3
    ds = NightPairs(three, crop=16, cache_bytes=2 * plane + 1)
    assert ds.preload() == 2
    assert ds.cached() == ["a.dng", "b.dng"]
    assert ds.preload() == 2  # again: nothing more
    assert NightPairs(three, crop=16, cache=1).preload() == 1
    assert NightPairs(three, crop=16, cache_bytes=0).preload() == 1  # the first always


def test_items_are_the_same_with_preload_here_and_in_a_forked_worker(three):
    ref = NightPairs(three, crop=16, seed=7, crops_per_image=2, cache=1)
    ref.set_epoch(2)
    want = [ref[i] for i in range(len(ref))]
    ds = NightPairs(three, crop=16, seed=7, crops_per_image=2)
    ds.set_epoch(2)
    assert ds.preload() == 3
    assert all(same(a, b) for a, b in zip(want, (ds[i] for i in range(len(ds)))))
    global PARENT
    PARENT = ds
    try:
        with mp.get_context("fork").Pool(1) as pool:
            kept, got = pool.apply(_items_of_parent, ([5, 0, 3],))
    finally:
        PARENT = None
    # the forked worker started with the images decoded here
    assert kept == ["a.dng", "b.dng", "c.dng"]
    assert all(same(want[i], g) for i, g in zip([5, 0, 3], got))
    assert pickle.loads(pickle.dumps(ds)).cached() == []
    assert ds.cached() == ["a.dng", "b.dng", "c.dng"]


def test_bad_bounds_are_refused(three):
    with pytest.raises(ValueError, match=r"cache 0: keep at least 1 decoded image"):
        NightPairs(three, crop=16, cache=0)
    with pytest.raises(ValueError, match=r"cache_bytes -1 must be at least 0"):
        NightPairs(three, crop=16, cache_bytes=-1)
    with pytest.raises(TypeError):
        NightPairs(three, crop=16, cache=2.5)
