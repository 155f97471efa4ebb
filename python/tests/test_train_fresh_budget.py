"""Fresh synthesis at the fixed row's budget (issue 35 item 4): an epoch of "Ours, fresh
synthesis" trains on as many patches as "Ours" (within 5 %), by drawing several crops per
day image (data.fresh_budget, experiment/unit.py fresh_set); and the loader gives the same
batches with 0 or 2 worker processes (items are functions of (seed, epoch, index))."""

import types

import numpy as np
import pytest

from conftest import FIXTURES, need_torch

import experiment_mini as mini


def test_budget_matches_the_fixed_grid():
    from day2night.train.data import fresh_budget, grid

    cases = [
        ([(3024, 4032)] * 60, 64, [3000] * 60),         # the paper: 60 images of 12 MP
        ([(124, 124)] * 3, 32, [120] * 3),              # the mini stand-ins
        ([(500, 700), (333, 1000), (90, 90)], 64, []),  # mixed sizes
        ([(128, 128)] * 2 + [(64, 200)], 32, [60, 60, 60]),
    ]
    for shapes, patch, sides in cases:
        crop, items = fresh_budget(shapes, patch, sides)
        fixed = sum(r * c for r, c in (grid(h, w, patch) for h, w in shapes))
        fresh = sum(items) * (crop // patch) ** 2
        assert abs(fresh - fixed) <= 0.05 * fixed, (shapes, crop, items, fresh, fixed)
        assert crop % patch == 0 and crop <= min([512, *sides, *(min(s) for s in shapes)])
    crop, items = fresh_budget([(3024, 4032)] * 60, 64, [3000] * 60)
    assert (crop, items[0]) == (512, 46)  # 60 x 46 x 64 = 176,640 against 177,660 fixed


@pytest.fixture(scope="module")
def stand_in(tmp_path_factory):
    root = tmp_path_factory.mktemp("fresh")
    days = mini.day_dir(root / "days", FIXTURES / "day.dng")
    return root, sorted(days.glob("*.dng"))


def fresh_set(root, files, patch, task):
    """unit.fresh_set over ``files`` (the options it reads: seed, patch, targets)."""
    from day2night.experiment import unit

    config = types.SimpleNamespace(seed=0, patch=patch, targets="day2night")
    return unit.fresh_set(root / "run" / "data" / "day-train", {f.name: f for f in files},
                          config, task)


@pytest.mark.parametrize("patch", [32, 64])
def test_fresh_epoch_has_the_fixed_rows_patches(stand_in, patch):
    need_torch()
    from day2night.experiment import pairs
    from day2night.train.data import FixedPatches

    root, files = stand_in
    fixed_x = [pairs.synth_pairs(f, "local", 0)["clean"] for f in files]
    fixed = FixedPatches([x for x, _ in fixed_x], [y for _, y in fixed_x], patch, patch)
    fresh = fresh_set(root, files, patch, "clean")
    n_fresh = len(fresh) * fresh.patches_per_item
    assert abs(n_fresh - len(fixed)) <= 0.05 * len(fixed), (n_fresh, len(fixed))
    # and the items really hold that many patches
    xs, ys = fresh[len(fresh) - 1]
    assert xs.shape == (fresh.patches_per_item, 3, patch, patch) == ys.shape


def test_same_batches_whatever_the_worker_count(stand_in):
    torch = need_torch()
    from day2night.train import trainer

    root, files = stand_in
    fresh = fresh_set(root, files, 32, "noisy")
    got = {}
    for workers in (0, 2):
        cfg = trainer.TrainConfig(out_dir=str(root / "w"), batch_size=32, workers=workers)
        loader, sampler = trainer.make_loader(fresh, cfg, 0, 1, shuffle=True)
        # with workers, the images are decoded here first, for the forked workers to share
        assert len(fresh.pairs.cached()) == (len(files) if workers else 0)
        sampler.set_epoch(3)
        fresh.set_epoch(3)
        got[workers] = [(x.clone(), y.clone()) for x, y in loader]
    assert len(got[0]) == len(got[2]) > 1
    for (x0, y0), (x2, y2) in zip(got[0], got[2]):
        assert torch.equal(x0, x2) and torch.equal(y0, y2)
    # the workers persist from epoch to epoch (the epoch rides with the indices): each
    # epoch's batches are still the in-process loader's of that epoch
    persistent, _ = trainer.make_loader(fresh, cfg, 0, 1, shuffle=False)
    plain, _ = trainer.make_loader(
        fresh, trainer.TrainConfig(out_dir=str(root / "w"), batch_size=32, workers=0), 0, 1,
        shuffle=False)
    assert persistent.persistent_workers and not plain.persistent_workers
    for epoch in (5, 6):
        fresh.set_epoch(epoch)
        want = list(plain)
        got_epoch = list(persistent)
        assert len(got_epoch) == len(want)
        for (x, y), (wx, wy) in zip(got_epoch, want):
            assert torch.equal(x, wx) and torch.equal(y, wy), epoch
    # another epoch draws other crops
    first = fresh[0][0].numpy()
    fresh.set_epoch(4)
    assert not np.array_equal(fresh[0][0].numpy(), first)
