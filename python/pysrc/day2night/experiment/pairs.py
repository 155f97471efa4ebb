"""Network input / target pairs of the experiment, made once and cached in the run folder.

- Real scene (test time, and real training slots): the clean task's input is the merged clean
  raw preprocessed with its own AsShotNeutral; the noisy task's input is the ISO's first
  frame, also with its AsShotNeutral; the target is the real-pairs PNG.
- Synthetic item (a day image of DAY_DIR): ``day2night.synthesize`` in the row's mode (``day``,
  ``dimmed``, ``global`` or ``local``), the network input preprocessed with the night neutral
  the synthesis reports (the average night illuminant under local relighting: the release's
  ``--wb-illum avg``), the target the clean night raw rendered with the same neutral.

Each pair is stored as ``<name>.x.npy`` (float32 H x W x 3) and ``<name>.y.npy`` (uint8
H x W x 3), written through a temporary file + rename; an existing pair is reused."""

import io
import pathlib

import numpy as np

from .atomic import write_bytes
from .png import read_png

NOISY_ISOS = (1600, 3200)


class PairError(ValueError):
    """A pair that cannot be made (the message names the scene or file)."""


def _npy_bytes(a):
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    return buf.getvalue()


def cached(folder, names, make):
    """{key: (x_path, y_path)} of stored pairs named ``names[key]``; ``make() -> {key: (x, y)}``
    runs when any of them is absent (one synthesis gives every key of a day image)."""
    folder = pathlib.Path(folder)
    paths = {k: (folder / f"{n}.x.npy", folder / f"{n}.y.npy") for k, n in names.items()}
    if not all(xp.is_file() and yp.is_file() for xp, yp in paths.values()):
        made = make()
        for k, (xp, yp) in paths.items():
            x, y = made[k]
            # y first: x present means the pair is complete
            write_bytes(yp, _npy_bytes(np.ascontiguousarray(y, np.uint8)))
            write_bytes(xp, _npy_bytes(np.ascontiguousarray(x, np.float32)))
    return paths


def load(path):
    return np.load(path, mmap_mode="r", allow_pickle=False)


def _read_dng(path, what):
    import day2night

    try:
        return day2night.read_dng(str(path))
    except (OSError, ValueError) as e:
        raise PairError(f"{what}: cannot read {path}: {e}") from None


def real_pair(scene, task_iso):
    """(x, y) of a real scene: ``task_iso`` None for the clean task, else the noisy ISO."""
    from ..train.preprocess import network_input

    if task_iso is None:
        raw = _read_dng(scene.clean_raw, f"scene {scene.id}")
    else:
        if task_iso not in scene.noisy:
            raise PairError(f"scene {scene.id}: no ISO {task_iso} input")
        raw = _read_dng(scene.noisy[task_iso], f"scene {scene.id}")
    x = network_input(raw)
    y = read_png(scene.target)
    aligned = align(x, y, raw.meta)
    if aligned is None:
        raise PairError(
            f"scene {scene.id}: target {scene.target} is {y.shape[1]}x{y.shape[0]}; the "
            f"network input of {raw.file_name} is {x.shape[1]}x{x.shape[0]} (active area), "
            "and neither its DefaultCrop + Orientation nor a quarter turn matches the target"
        )
    return aligned


def orient(img, orientation):
    """``img`` (H, W, ...) displayed as the TIFF/Exif Orientation tag (1..8) says."""
    o = int(orientation or 1)
    t = np.swapaxes(img, 0, 1)
    return {
        1: img,
        2: img[:, ::-1],
        3: img[::-1, ::-1],
        4: img[::-1],
        5: t,
        6: t[:, ::-1],
        7: t[::-1, ::-1],
        8: t[::-1],
    }.get(o, img)


def align(x, y, meta):
    """(x, y) with the same pixel grid, or None. The network input ``x`` covers the active
    area in sensor orientation; a target rendered with the ISP's defaults (as real-pairs
    writes it) is the DefaultCrop, oriented: ``x`` is cut and turned the same way. A target
    that is the active area turned a quarter (the release's portrait targets) is turned back,
    as the release's test.py does."""
    if x.shape == y.shape:
        return x, y
    crop = meta.get("default_crop")
    if crop:
        top, left, h, w = (int(round(float(v))) for v in crop)
        xc = orient(x[top : top + h, left : left + w], meta.get("orientation"))
        if xc.shape == y.shape:
            return np.ascontiguousarray(xc), y
    xo = orient(x, meta.get("orientation"))
    if xo.shape == y.shape:
        return np.ascontiguousarray(xo), y
    if np.rot90(y).shape == x.shape:
        return x, np.ascontiguousarray(np.rot90(y))
    return None


def synth_pairs(day_path, mode, seed, isos=NOISY_ISOS):
    """{key: (x, y)} of one day image synthesized in ``mode``: key ``"clean"`` and each ISO."""
    import day2night

    from ..train.preprocess import network_input
    from ..train.targets import render_target

    day = _read_dng(day_path, "day image")
    try:
        out = day2night.synthesize(day, seed=seed, mode=mode, isos=tuple(isos))
    except ValueError as e:
        raise PairError(f"{day_path}: synthesis ({mode}) failed: {e}") from None
    neutral = tuple(float(v) for v in out["neutral"])
    meta = dict(day.meta)
    meta["as_shot_neutral"] = list(neutral)
    clean = day2night.Raw.from_array(out["clean"], meta, name=day.name)
    y = render_target(clean, neutral=neutral)
    pairs = {"clean": (network_input(clean, neutral=neutral), y)}
    for iso in isos:
        noisy = day2night.Raw.from_array(np.asarray(out["noisy"][iso]), meta, name=day.name)
        pairs[iso] = (network_input(noisy, neutral=neutral), y)
    return pairs
