"""Training patches for the night ISP (torch map-style datasets).

- ``FixedPatches``: the release's fixed training set, every non-overlapping ``patch`` x
  ``patch`` crop on a stride grid of fixed (input, target) pairs (no augmentation). The
  images are kept once (per-image arrays or memory-mapped ``.npy`` files, see
  ``save_pair``/``FixedPatches.from_dir``: float32 arrays or ``cache`` stores, whose patch is
  demosaiced from its codes and a 1-pixel margin when asked for, the same bits) and a patch
  is cut when it is asked for: memory is the images' size, not the patches' (the release
  materializes every patch in RAM). The
  release also drops the first ``len % batch`` patches so that the count is a multiple of
  the batch; here the loader's last batch is simply smaller (``drop_last`` is not used).
- ``FreshPatches``: beyond the release, fresh synthesis every epoch. An item is one
  ``crop`` x ``crop`` synthesis of a ``NightPairs`` draw (a new night variant, crop position
  and ISO per epoch and index) cut into (crop/patch)^2 patches: input = the release's
  network input of the noisy (or clean) crop white-balanced by the image's average night
  illuminant, target = ``srgb8`` of the synthesized linear target / 255. One native call
  (``day2night._native.fresh_pair``) makes both, already cut: the numbers of
  ``synthesize(..., crop=...)`` put through ``preprocess.network_input_array`` (with its
  gamma table), ``targets.srgb8`` and ``cut``, bit for bit, without the arrays an item
  does not need (no other ISO's noise, no clean plane returned, no plan dict).

Both shard with ``torch.utils.data.DistributedSampler`` (``trainer`` does it under
torchrun): an item is a function of its index (and of the epoch for ``FreshPatches``).
Items: ``(x, y)`` float32 tensors, 3 x patch x patch for ``FixedPatches`` and
k x 3 x patch x patch for ``FreshPatches`` (``patches_per_item`` = k); ``collate`` stacks
either.
"""

import os

import numpy as np

from .._native import fresh_pair, synthesize
from ..atomic import open_atomic
from ..isos import NOISY_ISOS
from ..image_cache import CACHE_BYTES
from ..pairs import EpochSampler, NightPairs, epoch_index
from . import cache, preprocess, targets
from ._torch import Dataset, torch


def _load(a, mmap):
    if isinstance(a, (str, os.PathLike)):
        return np.load(os.fspath(a), mmap_mode="r" if mmap else None, allow_pickle=False)
    return np.asarray(a)


def _shape(a, name):
    """H x W x 3 of an input array or of an input store (``cache``)."""
    if cache.is_encoded(a):
        i = cache.info(a, name)
        return (i["height"], i["width"], 3)
    return a.shape


def _window(a, top, left, p):
    if cache.is_encoded(a):
        return cache.decode_window(a, top, left, p, p)
    return np.asarray(a[top:top + p, left:left + p], dtype=np.float32)


def save_pair(folder, name, x, y):
    """Store one fixed pair for ``FixedPatches.from_dir``: ``<name>_x.npy`` (the network
    input, H x W x 3 float32, in ``cache``'s exact store: about 2 bytes per pixel) and
    ``<name>_y.npy`` (the target, H x W x 3 uint8)."""
    os.makedirs(folder, exist_ok=True)
    x, y = np.asarray(x, dtype=np.float32), np.asarray(y)
    if y.dtype != np.uint8 or x.shape != y.shape or x.ndim != 3 or x.shape[2] != 3:
        raise ValueError(f"{name}: need x float32 H x W x 3 and y uint8 of the same shape, "
                         f"got {x.dtype} {x.shape} and {y.dtype} {y.shape}")
    for suffix, a in (("_x.npy", cache.encode(x)), ("_y.npy", y)):
        with open_atomic(os.path.join(folder, name + suffix)) as f:
            np.save(f, a)


class FixedPatches(Dataset):
    """Every non-overlapping ``patch`` x ``patch`` crop (top-left on a ``stride`` grid) of
    fixed pairs. ``inputs``: H x W x 3 float32 network inputs (arrays or ``.npy`` paths);
    ``targets``: H x W x 3 uint8 sRGB targets (arrays or paths), same sizes. Paths are
    memory-mapped (``mmap=True``). Item i: (x, y) float32 3 x patch x patch, y = target/255."""

    patches_per_item = 1

    def __init__(self, inputs, targets, patch=64, stride=64, mmap=True, names=None):
        if len(inputs) != len(targets):
            raise ValueError(f"{len(inputs)} inputs but {len(targets)} targets")
        if patch < 1 or stride < 1:
            raise ValueError(f"patch {patch} and stride {stride} must be positive")
        self.patch, self.stride = int(patch), int(stride)
        self.inputs = [_load(a, mmap) for a in inputs]
        self.targets = [_load(a, mmap) for a in targets]
        self.names = list(names) if names is not None else [str(i) for i in range(len(inputs))]
        counts = []
        for k, (x, y) in enumerate(zip(self.inputs, self.targets)):
            xs = _shape(x, self.names[k])
            if xs != y.shape or len(xs) != 3 or xs[2] != 3:
                raise ValueError(f"pair {self.names[k]}: input {xs} and target {y.shape} "
                                 "must both be H x W x 3 of the same size")
            if y.dtype != np.uint8:
                raise ValueError(f"pair {self.names[k]}: the target must be uint8 sRGB, got {y.dtype}")
            counts.append(grid(xs[0], xs[1], self.patch, self.stride))
        self.grid = counts
        self.offsets = np.concatenate([[0], np.cumsum([r * c for r, c in counts])]).astype(np.int64)
        if self.offsets[-1] == 0:
            raise ValueError(f"no {patch}x{patch} patch fits in any of the {len(inputs)} images")

    @classmethod
    def from_dir(cls, folder, patch=64, stride=64, mmap=True):
        """The pairs ``save_pair`` wrote to ``folder`` (sorted by name)."""
        names = sorted(f[:-6] for f in os.listdir(folder) if f.endswith("_x.npy"))
        if not names:
            raise ValueError(f"{folder}: no <name>_x.npy pair")
        xs = [os.path.join(folder, n + "_x.npy") for n in names]
        ys = [os.path.join(folder, n + "_y.npy") for n in names]
        for y in ys:
            if not os.path.isfile(y):
                raise ValueError(f"{y}: missing (its input {y[:-6]}_x.npy exists)")
        return cls(xs, ys, patch, stride, mmap, names)

    def __len__(self):
        return int(self.offsets[-1])

    def locate(self, index):
        """(image index, top, left) of patch ``index``."""
        if not 0 <= index < len(self):
            raise IndexError(f"patch {index} out of range for {len(self)} patches")
        k = int(np.searchsorted(self.offsets, index, side="right") - 1)
        r, c = divmod(int(index - self.offsets[k]), self.grid[k][1])
        return k, r * self.stride, c * self.stride

    def __getitem__(self, index):
        k, top, left = self.locate(int(index))
        p = self.patch
        x = _window(self.inputs[k], top, left, p)
        y = np.asarray(self.targets[k][top:top + p, left:left + p], dtype=np.float32) / np.float32(255)
        return (torch.from_numpy(np.ascontiguousarray(x.transpose(2, 0, 1))),
                torch.from_numpy(np.ascontiguousarray(y.transpose(2, 0, 1))))


def grid(h, w, patch, stride=None):
    """(rows, cols) of the ``patch`` x ``patch`` crops on a ``stride`` grid of an h x w image
    (every non-overlapping crop when ``stride`` = ``patch``, the release's patches)."""
    stride = patch if stride is None else stride
    rows = (h - patch) // stride + 1 if h >= patch else 0
    cols = (w - patch) // stride + 1 if w >= patch else 0
    return rows, cols


def cut(a, patch):
    """H x W x 3 -> (H/patch * W/patch) x 3 x patch x patch (row-major grid, remainder dropped)."""
    h, w = a.shape[0] // patch, a.shape[1] // patch
    a = a[:h * patch, :w * patch]
    return np.ascontiguousarray(
        a.reshape(h, patch, w, patch, 3).transpose(0, 2, 4, 1, 3).reshape(h * w, 3, patch, patch))


class FreshPatches(Dataset):
    """Fresh synthesis: item i of epoch e is the ``crop`` x ``crop`` night synthesis
    ``NightPairs(day_dir, crop, isos, seed, crops_per_image)`` draws for (e, i), cut into
    (crop/patch)^2 patches. ``task``: "noisy" (input = the noisy raw of the drawn ISO) or
    "clean" (the clean night raw). ``gamma`` as ``preprocess.network_input``. ``cache`` and
    ``cache_bytes`` bound the decoded images kept per process, as ``NightPairs``'
    (``preload()`` decodes them before a loader forks its workers). Other keyword arguments
    are ``synthesize`` options (bulbs, noise_model, ...)."""

    def __init__(self, day_dir, crop=512, patch=64, isos=NOISY_ISOS, seed=0,
                 crops_per_image=1, task="noisy", gamma=preprocess.GAMMA, mode="local",
                 items_per_image=None, cache=None, cache_bytes=CACHE_BYTES, **options):
        if task not in ("noisy", "clean"):
            raise ValueError(f"task {task!r}: use 'noisy' or 'clean'")
        if crop % patch or crop < patch:
            raise ValueError(f"crop {crop} must be a multiple of the patch {patch}")
        counts = None if items_per_image is None else [int(n) for n in items_per_image]
        if counts is not None:
            if any(n < 0 for n in counts) or not sum(counts):
                raise ValueError(f"items_per_image {counts}: need counts >= 0, not all 0")
            crops_per_image = max(counts)
        self.pairs = NightPairs(day_dir, crop=crop, isos=isos, seed=seed,
                                crops_per_image=crops_per_image, mode=mode, cache=cache,
                                cache_bytes=cache_bytes, **options)
        if counts is not None and len(counts) != len(self.pairs.files):
            raise ValueError(f"items_per_image has {len(counts)} counts for "
                             f"{len(self.pairs.files)} day images in {day_dir}")
        self.counts = counts
        self.starts = None if counts is None else np.cumsum([0] + counts)
        self.task, self.patch, self.gamma = task, int(patch), gamma
        self.mode, self.options, self.seed = mode, dict(options), seed
        self.patches_per_item = (crop // patch) ** 2

    def __len__(self):
        return len(self.pairs) if self.counts is None else int(self.starts[-1])

    def pair_index(self, index):
        """The ``NightPairs`` item of item ``index``: with ``items_per_image``, the j-th item
        of image k is ``NightPairs`` item k * max(counts) + j (its draws: (seed, epoch, that
        index)), so an item never depends on the loader's workers or order."""
        if not 0 <= index < len(self):
            raise IndexError(f"item {index} out of range for {len(self)} items")
        if self.counts is None:
            return index
        k = int(np.searchsorted(self.starts, index, side="right") - 1)
        return k * self.pairs.crops_per_image + int(index - self.starts[k])

    def set_epoch(self, epoch):
        self.pairs.set_epoch(epoch)

    def preload(self):
        """``NightPairs.preload``: decode the day images in this process (within the cache's
        bounds) so that the loader's forked workers share them; returns how many are kept."""
        return self.pairs.preload()

    @property
    def epoch(self):
        return self.pairs.epoch

    def _pair(self, index, patch, out=None):
        epoch, index = epoch_index(index)
        q = self.pairs.place(self.pair_index(index), epoch)
        return fresh_pair(q["raw"], q["crop"], q["iso"], seed=self.seed, variant=q["variant"],
                          mode=self.mode, task=self.task, table=preprocess._table(self.gamma),
                          patch=patch, out=out, **self.options)

    def arrays(self, index):
        """(input H x W x 3 float32, target H x W x 3 uint8) of item ``index``."""
        return self._pair(index, None)

    def reference_arrays(self, index):
        """``arrays(index)`` computed the long way: ``synthesize`` of the crop, then
        ``preprocess.network_input_array`` and ``targets.srgb8`` in numpy (the same numbers;
        for tests and benches)."""
        q = self.pairs.place(self.pair_index(index))
        raw, (top, left, h, w) = q["raw"], q["crop"]
        out = synthesize(raw, seed=self.seed, variant=q["variant"], mode=self.mode,
                         isos=(q["iso"],), crop=q["crop"], **self.options)
        plane = out["noisy"][q["iso"]] if self.task == "noisy" else out["clean"]
        x = preprocess.network_input_array(plane, raw.meta, out["neutral"], top, left, self.gamma)
        return x, targets.srgb8(out["target"])

    def __getitem__(self, index):
        """Item ``index`` of the current epoch, or of epoch e for an (e, index) pair (what
        ``pairs.EpochSampler`` gives persistent workers)."""
        xs, ys = self._pair(index, self.patch)
        return torch.from_numpy(xs), torch.from_numpy(ys)

    def __getitems__(self, indices):
        """The items ``indices`` as one batch (what a ``DataLoader`` asks for): each item's
        patches are written by the native call straight into its rows of the batch's two
        tensors, in shared memory inside a worker, so that ``collate`` passes them on
        without a copy (docs/benchmarks.md, the training loader)."""
        k, p = self.patches_per_item, self.patch
        x, y = (_batch_tensor((len(indices) * k, 3, p, p)) for _ in range(2))
        xa, ya = x.numpy(), y.numpy()
        for j, index in enumerate(indices):
            self._pair(index, p, out=(xa[j * k:(j + 1) * k], ya[j * k:(j + 1) * k]))
        return Batch(x, y)


def fresh_budget(shapes, patch=64, sides=(), max_crop=512, tolerance=0.05):
    """(crop, items per image) for fresh synthesis to train on as many patches per epoch as
    the fixed set of the same images: ``shapes`` are the fixed inputs' (H, W), whose
    stride-``patch`` grids hold the fixed patches; ``sides`` the largest square crop each
    image allows (its DefaultCrop). The largest crop (a multiple of ``patch``, at most
    ``max_crop``) whose rounded counts give the fixed total within ``tolerance`` wins; a
    crop of one patch always matches exactly."""
    fixed = [r * c for r, c in (grid(h, w, patch) for h, w in shapes)]
    total = sum(fixed)
    if not total:
        raise ValueError(f"no {patch}x{patch} patch fits in any of the {len(shapes)} images")
    side = min([max_crop, *sides, *(min(h, w) for h, w in shapes)])
    for crop in range(side // patch * patch, patch - 1, -patch):
        per = (crop // patch) ** 2
        items = [int(np.floor(n / per + 0.5)) for n in fixed]
        if sum(items) and abs(sum(items) * per - total) <= tolerance * total:
            return crop, items
    raise ValueError(f"images smaller than one {patch}x{patch} patch")


class Batch(tuple):
    """(x, y) of items already made as one batch (``FreshPatches.__getitems__``)."""

    def __new__(cls, x, y):
        return super().__new__(cls, (x, y))


def collate(batch):
    """Stack items of either dataset into (N x 3 x p x p, N x 3 x p x p); a ``Batch`` is
    already that."""
    if isinstance(batch, Batch):
        return batch[0], batch[1]
    xs = [b[0] if b[0].dim() == 4 else b[0].unsqueeze(0) for b in batch]
    ys = [b[1] if b[1].dim() == 4 else b[1].unsqueeze(0) for b in batch]
    return _cat(xs), _cat(ys)


def _batch_tensor(shape):
    """An uninitialized float32 tensor of ``shape``; in a DataLoader worker in shared memory
    (as ``_cat`` makes its batches), so that it reaches the main process without a copy."""
    if torch.utils.data.get_worker_info() is not None:
        try:
            t = torch.empty(0, dtype=torch.float32)
            storage = t._typed_storage()._new_shared(int(np.prod(shape)))
            return t.new(storage).resize_(*shape)
        except (AttributeError, RuntimeError):
            pass  # a torch without these internals: private memory, copied by torch
    return torch.empty(shape, dtype=torch.float32)


def _cat(ts):
    """``torch.cat(ts)``; in a DataLoader worker straight into shared memory, as torch's own
    ``default_collate`` does, so that the batch is not copied once more to reach the main
    process (docs/benchmarks.md, the training loader)."""
    out = None
    if torch.utils.data.get_worker_info() is not None:
        try:
            storage = ts[0]._typed_storage()._new_shared(sum(t.numel() for t in ts))
            out = ts[0].new(storage).resize_(sum(t.shape[0] for t in ts), *ts[0].shape[1:])
        except (AttributeError, RuntimeError):
            out = None  # a torch without these internals: the plain copy
    return torch.cat(ts, out=out)
