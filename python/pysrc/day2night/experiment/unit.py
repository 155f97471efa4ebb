"""One training unit: train (or resume) a UNet on the unit's pairs, then score it on the real
test scenes, keeping the images the report shows. Imports torch (through day2night.train)."""

import pathlib

import numpy as np

from ..isos import NOISY_ISOS
from .. import delta_e2000_map
from . import pairs
from ..png import write_png


def _fresh_set(exp, task):
    """Fresh synthesis over the training day images (a folder of links to them), at the
    fixed "Ours" row's budget: as many patches per epoch as the stride-``patch`` grids of
    the fixed inputs hold (``data.fresh_budget``: crops per image from each image's area)."""
    from ..train.data import FreshPatches, fresh_budget

    import day2night

    folder = exp.out / "data" / "day-train"
    folder.mkdir(parents=True, exist_ok=True)
    shapes, sides = {}, {}
    for name in exp.day_train:
        link = folder / name.replace("/", "__")
        if not link.exists():
            link.symlink_to(pathlib.Path(exp.days[name]).resolve())
        raw = day2night.read_dng(str(exp.days[name]))
        shapes[link.name], sides[link.name] = _fixed_shape(exp, raw)
    files = sorted(shapes)  # NightPairs' order
    patch = exp.cfg.get("patch", 64)
    crop, items = fresh_budget([shapes[f] for f in files], patch, [sides[f] for f in files])
    return FreshPatches(str(folder), crop=crop, patch=patch, isos=NOISY_ISOS,
                        seed=exp.cfg["seed"], task=task, items_per_image=items)


def _fixed_shape(exp, raw):
    """((H, W) of the fixed row's network input of ``raw``, the side of the largest square
    crop inside its DefaultCrop): the active area, or the release's window of it when the
    targets are the release's (pairs.align cuts the input to it)."""
    h, w = raw.data.shape[:2]
    area, crop = raw.meta.get("active_area"), raw.meta.get("default_crop")
    if area:
        h, w = int(area[2]) - int(area[0]), int(area[3]) - int(area[1])
    shape = (h, w)
    if exp.cfg.get("targets") == "release":
        shape = tuple(pairs.release_window(raw.meta, h, w)[2:])
    side = min(int(crop[2]), int(crop[3])) if crop else min(h, w)
    return shape, side


def train_unit(exp, udir, task, row, train_p, val_p):
    from ..train.data import FixedPatches
    from ..train.trainer import TrainConfig, train

    c = exp.cfg
    patch = c.get("patch", 64)
    val_set = FixedPatches([x for x, _ in val_p], [y for _, y in val_p], patch, patch)
    if train_p is None:
        train_set = _fresh_set(exp, task)
    else:
        train_set = FixedPatches([x for x, _ in train_p], [y for _, y in train_p], patch, patch)
    cfg = TrainConfig(
        out_dir=str(udir / "model"),
        epochs=c["epochs"],
        batch_size=c.get("batch", 128),
        lr=c.get("lr", 1e-3),
        init_features=c["width"],
        seed=c["seed"],
        device=c["device"],
        workers=getattr(exp, "workers", 0),
        amp=c.get("amp"),
        channels_last=c.get("channels_last", False),
        progress=True,
    )
    return train(cfg, train_set, val_set)


def _u8(x):
    return (np.clip(np.asarray(x, np.float32), 0, 1) * 255).astype(np.uint8)


def heat(de, scale=10.0):
    """A Delta E map as an 8-bit greyscale image: 0 black, ``scale`` and more white."""
    return (np.clip(de / scale, 0, 1) * 255).astype(np.uint8)


def score_unit(exp, udir, task, row, fold, tests, result):
    from ..train.infer import predict
    from ..train.scores import score
    from ..train.trainer import load_model

    device = exp.cfg["device"]
    model = load_model(result["best"], device=device)
    images = []
    for sid, key, (xp, yp) in tests:
        x, y = pairs.load(xp), np.asarray(pairs.load(yp))
        pred = predict(model, np.asarray(x), device=device, amp=exp.cfg.get("amp"),
                       channels_last=exp.cfg.get("channels_last", False))
        s = score(pred, y)
        images.append(
            {"scene": sid, "input": str(key), "psnr": _num(s["psnr"]), "ssim": _num(s["ssim"]),
             "delta_e": _num(s["delta_e"])}
        )
        if sid in exp.report_scenes:
            img = exp.out / "img" / task / row.id
            stem = f"{sid}_{key}"
            write_png(img / f"{stem}_pred.png", pred)
            de = delta_e2000_map(pred / 255.0, y / 255.0, pred_linear=False, target_linear=False)
            write_png(img / f"{stem}_de.png", heat(de))
            shared = exp.out / "img" / task / "scenes"
            if not (shared / f"{stem}_target.png").is_file():
                write_png(shared / f"{stem}_input.png", _u8(x))
                write_png(shared / f"{stem}_target.png", y)
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
        "images": images,
    }


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
