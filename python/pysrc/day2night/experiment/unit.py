"""One training unit: train (or resume) a UNet on the unit's pairs, then score it on the real
test scenes, keeping the images the report shows. Imports torch (through day2night.train)."""

import pathlib

import numpy as np

import day2night

from ..isos import NOISY_ISOS
from .. import delta_e2000_map
from . import demap, names, pairs
from ..variants import Isp
from ..png import write_png
from ..train.config import TrainConfig
from ..train.data import FixedPatches, FreshPatches, fresh_budget
from ..train.infer import predict
from ..train.scores import score
from ..train.trainer import load_model, make_model, train


def fresh_set(folder, days, config, task):
    """Fresh synthesis over the training day images ``days`` ({name: day DNG}, in order)
    through ``folder``, a folder of links to them, at the fixed "Ours" row's budget: as many
    patches per epoch as the stride-``patch`` grids of the fixed inputs hold
    (``data.fresh_budget``: crops per image from each image's area)."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    shapes, sides = {}, {}
    for name, path in days.items():
        link = folder / names.day_link(name)
        if not link.exists():
            try:
                link.symlink_to(pathlib.Path(path).resolve())
            except FileExistsError:  # made by a unit running beside this one (--ray)
                pass
        raw = day2night.read_dng(str(path))
        shapes[link.name], sides[link.name] = _fixed_shape(config.targets, raw)
    files = sorted(shapes)  # NightPairs' order
    crop, items = fresh_budget([shapes[f] for f in files], config.patch,
                               [sides[f] for f in files])
    return FreshPatches(str(folder), crop=crop, patch=config.patch, isos=NOISY_ISOS,
                        seed=config.seed, task=task, items_per_image=items)


def _fixed_shape(targets, raw):
    """((H, W) of the fixed row's network input of ``raw``, the side of the largest square
    crop inside its DefaultCrop): the active area, or the release's window of it when the
    ``targets`` are the release's (pairs.align cuts the input to it)."""
    h, w = raw.data.shape[:2]
    area, crop = raw.meta.get("active_area"), raw.meta.get("default_crop")
    if area:
        h, w = int(area[2]) - int(area[0]), int(area[3]) - int(area[1])
    shape = (h, w)
    if targets == Isp.RELEASE:
        shape = tuple(pairs.release_window(raw.meta, h, w)[2:])
    side = min(int(crop[2]), int(crop[3])) if crop else min(h, w)
    return shape, side


def fixed_set(pairs_, patch):
    """The patches of stored (x_path, y_path) pairs (``data.FixedPatches``)."""

    return FixedPatches([x for x, _ in pairs_], [y for _, y in pairs_], patch, patch)


def train_config(config, model_dir):
    """The trainer's TrainConfig of an ExperimentConfig (its checkpoints in ``model_dir``)."""

    c = config
    return TrainConfig(out_dir=str(model_dir), epochs=c.epochs, batch_size=c.batch, lr=c.lr,
                       init_features=c.width, seed=c.seed, device=c.device, workers=c.workers,
                       amp=c.amp, channels_last=c.channels_last, progress=True)


def train_unit(config, model_dir, val_p, train_set):
    """Train (or resume, from ``model_dir``) on ``train_set`` (a callable giving the data
    set: :func:`fixed_set`, :func:`fresh_set`), validated on the pairs ``val_p``."""

    val_set = fixed_set(val_p, config.patch)
    return train(train_config(config, model_dir), train_set(), val_set)


def _u8(x):
    return (np.clip(np.asarray(x, np.float32), 0, 1) * 255).astype(np.uint8)


def heat(de):
    """A Delta E map as an 8-bit sRGB image in the report's colour map (demap.py: viridis,
    logarithmic, 0 to demap.DE_MAX)."""
    return demap.colour(de)


def score_unit(config, out, task, row, fold, tests, result, report_scenes):
    """The unit's scores.json record: ``result`` (train's) scored on ``tests``
    (PairSource.tests); the images of ``report_scenes`` written under ``out``/img."""

    model = load_model(result["best"], device=config.device)
    # the epochs' numbers without their timings (table.json is the same on every rerun)
    history = [
        {k: _num(v) for k, v in h.items() if k != "seconds"} for h in result.get("history", [])
    ]
    return {
        "task": task,
        "row": row.id,
        "fold": fold,
        "history": history,
        # the untrained weights' validation (the start of the report's curves)
        "initial": {k: _num(v) for k, v in (result.get("initial") or {}).items()},
        "images": score_model(config, model, out, task, row, tests, report_scenes),
    }


def score_untrained(config, out, task, row, fold, tests, report_scenes):
    """The scores.json record of the untrained row: the initial weights of a unit trained
    with ``config`` (``trainer.make_model``: ``torch.manual_seed(config.seed)``, width
    ``config.width``), not trained, scored like :func:`score_unit` (no history)."""
    model = make_model(train_config(config, None)).to(config.device).eval()
    return {"task": task, "row": row.id, "fold": fold, "history": [], "initial": {},
            "images": score_model(config, model, out, task, row, tests, report_scenes)}


def score_model(config, model, out, task, row, tests, report_scenes):
    """The per-image scores of ``model`` on ``tests`` (PairSource.tests), as scores.json's
    "images"; the images of ``report_scenes`` written under ``out``/img."""
    images = []
    for sid, key, (xp, yp) in tests:
        x, y = pairs.load(xp), np.asarray(pairs.load(yp))
        pred = predict(model, np.asarray(x), device=config.device, amp=config.amp,
                       channels_last=config.channels_last)
        s = score(pred, y)
        images.append(
            {"scene": sid, "input": str(key), "psnr": _num(s["psnr"]), "ssim": _num(s["ssim"]),
             "delta_e": _num(s["delta_e"])}
        )
        if sid in report_scenes:
            _report_images(pathlib.Path(out) / "img" / task, row.id, names.image_stem(sid, key),
                           x, y, pred)
    return images


def _report_images(img, row_id, stem, x, y, pred):
    """The report's PNGs of one test input: the prediction and its Delta E map per row, the
    input and target once per task (``img``: RUN/img/<task>)."""
    write_png(img / row_id / f"{stem}_pred.png", pred)
    de = delta_e2000_map(pred / 255.0, y / 255.0, pred_linear=False, target_linear=False)
    write_png(img / row_id / f"{stem}_de.png", heat(de))
    shared = img / "scenes"
    if not (shared / f"{stem}_target.png").is_file():
        write_png(shared / f"{stem}_input.png", _u8(x))
        write_png(shared / f"{stem}_target.png", y)


def _num(v):
    """A JSON-safe float (inf/nan as strings, so table.json stays standard JSON)."""
    if v is None:
        return None
    f = float(v)
    if f != f:
        return "nan"
    if f in (float("inf"), float("-inf")):
        return "inf" if f > 0 else "-inf"
    return f
