"""One training unit: train (or resume) a UNet on the unit's pairs, then score it on the real
test scenes, keeping the images the report shows. Imports torch (through day2night.train)."""

import pathlib

import numpy as np

from . import deltae, pairs
from .png import write_png


def _fresh_set(exp, task):
    """Fresh synthesis over the training day images (a folder of links to them)."""
    from ..train.data import FreshPatches

    import day2night

    folder = exp.out / "data" / "day-train"
    folder.mkdir(parents=True, exist_ok=True)
    side = None
    for name in exp.day_train:
        link = folder / name.replace("/", "__")
        if not link.exists():
            link.symlink_to(pathlib.Path(exp.days[name]).resolve())
        raw = day2night.read_dng(str(exp.days[name]))
        h, w = raw.data.shape[:2]
        area, crop = raw.meta.get("active_area"), raw.meta.get("default_crop")
        if crop:  # fresh crops are drawn inside the DefaultCrop
            h, w = int(crop[2]), int(crop[3])
        elif area:
            h, w = area[2] - area[0], area[3] - area[1]
        side = min(side or 512, h, w)
    crop = max(64, side // 64 * 64)
    return FreshPatches(str(folder), crop=crop, patch=64, isos=(1600, 3200),
                        seed=exp.cfg["seed"], task=task)


def train_unit(exp, udir, task, row, train_p, val_p):
    from ..train.data import FixedPatches
    from ..train.trainer import TrainConfig, train

    val_set = FixedPatches([x for x, _ in val_p], [y for _, y in val_p])
    if train_p is None:
        train_set = _fresh_set(exp, task)
    else:
        train_set = FixedPatches([x for x, _ in train_p], [y for _, y in train_p])
    cfg = TrainConfig(
        out_dir=str(udir / "model"),
        epochs=exp.cfg["epochs"],
        init_features=exp.cfg["width"],
        seed=exp.cfg["seed"],
        device=exp.cfg["device"],
        progress=True,
    )
    return train(cfg, train_set, val_set)


def _u8(x):
    return (np.clip(np.asarray(x, np.float32), 0, 1) * 255).astype(np.uint8)


def score_unit(exp, udir, task, row, fold, tests, result):
    from ..train.infer import predict
    from ..train.scores import score
    from ..train.trainer import load_model

    device = exp.cfg["device"]
    model = load_model(result["best"], device=device)
    images = []
    for sid, key, (xp, yp) in tests:
        x, y = pairs.load(xp), np.asarray(pairs.load(yp))
        pred = predict(model, np.asarray(x), device=device)
        s = score(pred, y)
        images.append(
            {"scene": sid, "input": str(key), "psnr": _num(s["psnr"]), "ssim": _num(s["ssim"]),
             "delta_e": _num(s["delta_e"])}
        )
        if sid in exp.report_scenes:
            img = exp.out / "img" / task / row.id
            stem = f"{sid}_{key}"
            write_png(img / f"{stem}_pred.png", pred)
            write_png(img / f"{stem}_de.png", deltae.heat(deltae.delta_e_map(pred, y)))
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
