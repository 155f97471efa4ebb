"""``NightPairs``: fresh night training pairs on random crops, as a map-style dataset.

Each item is a deterministic function of (seed, epoch, index): the image, the variant
(a new plan of lights, illuminants and dimming), the crop position and the ISO are drawn
from a SHA-256 of those three numbers, so an item is the same in any worker process and
in any order, and ``set_epoch`` draws new variants and crops. No torch import: the items
are dicts of numpy arrays that ``torch.utils.data.default_collate`` stacks.
"""

import hashlib
import operator
import os
import random

import numpy as np

from ._native import check_int, night_pair
from .image_cache import CACHE_BYTES, DecodedImages
from .isos import NOISY_ISOS


def pack_bayer(plane, meta, top=0, left=0):
    """Pack a Bayer plane (H x W, H and W even) into 4 x H/2 x W/2 float32, normalized by the
    black and white levels: ``(x - black) / (white - max(black))`` per 2x2 position, in the
    order of the CFA positions (0,0), (0,1), (1,0), (1,1) (R, G, G, B for RGGB).

    ``top``/``left`` are the plane's offset in the active area (they select the phase of a
    BlackLevel pattern; even offsets keep the CFA phase). BlackLevelDeltaH/V are not applied.

    >>> x = pack_bayer(out["noisy"][1600], raw.meta)
    >>> x.shape
    (4, 256, 256)
    """
    plane = np.asarray(plane)
    h, w = plane.shape
    if h % 2 or w % 2:
        raise ValueError(f"pack_bayer needs an even-sized plane, got {h}x{w}")
    black = [float(b) for b in meta["black_level"]]
    rr, rc = meta["black_level_repeat_dim"]
    white = float(meta["white_level"])
    scale = white - max(black)
    if not scale > 0:
        raise ValueError(f"black level {max(black)} >= white level {white}")
    out = np.empty((4, h // 2, w // 2), dtype=np.float32)
    for i in range(2):
        for j in range(2):
            b = black[((top + i) % rr) * rc + (left + j) % rc]
            out[2 * i + j] = (plane[i::2, j::2].astype(np.float32) - np.float32(b)) / np.float32(scale)
    return out


def _draw(seed, epoch, index):
    """The random stream of one item: SHA-256 of (seed, epoch, index), the same in every
    process (Python's ``hash`` is salted per process, so it is not used)."""
    key = hashlib.sha256(f"day2night NightPairs v1 {seed} {epoch} {index}".encode()).digest()
    return random.Random(int.from_bytes(key, "little"))


def epoch_index(index):
    """(epoch or None, index) of an item index or of an (epoch, index) pair (EpochSampler)."""
    if isinstance(index, tuple):
        epoch, index = index
        return int(epoch), int(index)
    return None, int(index)


class EpochSampler:
    """``sampler``'s indices as (epoch, index) pairs, with the epoch of ``dataset`` when an
    epoch's iteration starts. Persistent ``DataLoader`` workers keep their own copy of the
    dataset, which ``set_epoch`` in the main process does not reach; with these pairs they
    still make each epoch's items (``NightPairs`` and ``FreshPatches`` take them).

    >>> loader = torch.utils.data.DataLoader(ds, sampler=EpochSampler(sampler, ds),
    ...                                      num_workers=2, persistent_workers=True)"""

    def __init__(self, sampler, dataset):
        self.sampler, self.dataset = sampler, dataset

    def __iter__(self):
        epoch = self.dataset.epoch  # now, not at the first item
        return ((epoch, i) for i in self.sampler)

    def __len__(self):
        return len(self.sampler)


class NightPairs:
    """Map-style dataset of fresh night pairs synthesized on random crops of day DNGs.

    Parameters: ``day_dir`` (a folder of ``.dng`` files, sorted by name), ``crop`` (side of
    the square crop, even), ``isos`` (each item draws one), ``seed``, ``crops_per_image``
    (items per image and epoch), ``mode`` and any ``synthesize`` option (``bulbs``,
    ``noise_model``, ...). Decoded images are kept per process, least recently used out
    first: at most ``cache`` of them (None: no count limit) and at most ``cache_bytes`` of
    their planes (4 GiB by default, enough for the 60 training images of the paper's
    experiment at 12 MP: 1.5 GB). An image that is not kept is decoded again for each of
    its items, which costs about ten times the item itself (docs/benchmarks.md, "Fresh
    synthesis over many images"). ``preload()`` decodes them up front: call it before a
    DataLoader starts its worker processes, which then share the decoded images.

    Each item is a dict: ``noisy`` (4 x crop/2 x crop/2 float32, the noisy Bayer crop packed
    and normalized), ``clean`` (the same for the clean raw), ``target`` (3 x crop x crop
    float32, linear Rec.709), ``iso``, ``name``, ``variant``, ``origin`` ((top, left) of the
    crop in the active area).

    >>> ds = NightPairs("day/", crop=512, isos=(1600, 3200), seed=0)
    >>> item = ds[0]
    >>> item["noisy"].shape, item["target"].shape
    ((4, 256, 256), (3, 512, 512))
    >>> ds.preload()              # the workers (forked) share the decoded images
    >>> loader = torch.utils.data.DataLoader(ds, batch_size=8, num_workers=2)
    >>> for epoch in range(10):
    ...     ds.set_epoch(epoch)   # persistent workers: sampler=EpochSampler(sampler, ds)
    ...     for batch in loader: ...
    """

    def __init__(self, day_dir, crop=512, isos=NOISY_ISOS, seed=0, crops_per_image=1,
                 mode="local", cache=None, cache_bytes=CACHE_BYTES, **options):
        self.day_dir = os.fspath(day_dir)
        if not os.path.isdir(self.day_dir):
            raise ValueError(f"{self.day_dir}: not a folder")
        self.files = sorted(
            f for f in os.listdir(self.day_dir)
            if f.lower().endswith(".dng") and os.path.isfile(os.path.join(self.day_dir, f))
        )
        if not self.files:
            raise ValueError(f"{self.day_dir}: no .dng file")
        crop = operator.index(crop)
        if crop <= 0 or crop % 2:
            raise ValueError(f"crop {crop} must be a positive even number of samples")
        self.crop = crop
        # The command line's bounds (BOUNDS), checked here rather than at the first item.
        self.isos = tuple(check_int("iso", i, f"isos[{k}]") for k, i in enumerate(isos))
        if not self.isos:
            raise ValueError(f"isos {isos!r}: give one or more ISOs")
        self.seed = check_int("seed", seed)
        self.crops_per_image = operator.index(crops_per_image)
        if self.crops_per_image < 1:
            raise ValueError("crops_per_image must be at least 1")
        self.mode = mode
        self.options = dict(options)
        self.images = DecodedImages(self.day_dir, cache, cache_bytes)
        self.epoch = 0

    def __len__(self):
        return len(self.files) * self.crops_per_image

    def set_epoch(self, epoch):
        """Draw new variants and crops: items are functions of (seed, epoch, index)."""
        self.epoch = int(epoch)

    def cached(self):
        """The names of the images this process keeps decoded, least recently used first."""
        return self.images.names()

    def preload(self):
        """Decode the images in name order while the cache keeps them (``cache`` images,
        ``cache_bytes``), each with the per-image work of its first item done (the noise
        estimate of an input without a NoiseProfile), and return how many are kept. Worker
        processes that a DataLoader forks afterwards share them (a pickle carries no decoded
        image: under the spawn start method each worker decodes its own)."""
        for name in self.files:
            kept = self.images.add(name)
            if kept is None:
                break
            raw, (y0, x0, _, _) = kept
            # the first item's per-image work (the noise estimate), on the smallest crop
            night_pair(raw, self.seed, 0, self.isos[0], (y0 + y0 % 2, x0 + x0 % 2, 2, 2),
                       mode=self.mode, **self.options)
        return len(self.images)

    def params(self, index, epoch=None):
        """The draws of item ``index`` at ``epoch`` (None: the current one): file, variant,
        ISO and the crop's (top, left) as fractions to be placed inside the image's
        DefaultCrop."""
        if not 0 <= index < len(self):
            raise IndexError(f"index {index} out of range for {len(self)} items")
        rng = _draw(self.seed, self.epoch if epoch is None else int(epoch), index)
        return {
            "file": self.files[index // self.crops_per_image],
            "variant": rng.randrange(2**31),
            "iso": self.isos[rng.randrange(len(self.isos))],
            "u": rng.random(),
            "v": rng.random(),
        }

    def place(self, index, epoch=None):
        """Where item ``index`` of ``epoch`` (None: the current one) is synthesized: a dict
        with ``raw`` (the decoded image), ``variant``, ``iso`` and ``crop`` ((top, left,
        height, width) in active-area coordinates: an even position inside the image's
        DefaultCrop)."""
        if index < 0:
            index += len(self)
        p = self.params(index, epoch)
        raw, (y0, x0, ch, cw) = self.images.get(p["file"])
        c = self.crop
        if c > ch or c > cw:
            raise ValueError(f"{raw.path}: crop {c} is larger than the image's {cw}x{ch} DefaultCrop")
        # Even positions inside the DefaultCrop (the target then equals the frame's region).
        lo_t, lo_l = y0 + (y0 % 2), x0 + (x0 % 2)
        hi_t, hi_l = y0 + ch - c, x0 + cw - c
        if hi_t < lo_t or hi_l < lo_l:
            raise ValueError(f"{raw.path}: no even crop position of {c} inside the DefaultCrop")
        top = lo_t + 2 * int(p["u"] * ((hi_t - lo_t) // 2 + 1))
        left = lo_l + 2 * int(p["v"] * ((hi_l - lo_l) // 2 + 1))
        top, left = min(top, hi_t - (hi_t - lo_t) % 2), min(left, hi_l - (hi_l - lo_l) % 2)
        return {"raw": raw, "variant": p["variant"], "iso": p["iso"], "crop": (top, left, c, c)}

    def __getitem__(self, index):
        """Item ``index`` of the current epoch, or of epoch e for an (e, index) pair."""
        epoch, index = epoch_index(index)
        q = self.place(index, epoch)
        raw, iso, (top, left, _, _) = q["raw"], q["iso"], q["crop"]
        # One call: the synthesis of the crop and the arrays in their final layout (Rust).
        out = night_pair(raw, self.seed, q["variant"], iso, q["crop"], mode=self.mode,
                         **self.options)
        out["iso"] = iso
        out["name"] = raw.name
        out["variant"] = q["variant"]
        out["origin"] = np.array([top, left], dtype=np.int64)
        return out
