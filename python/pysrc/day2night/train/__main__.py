"""``python -m day2night.train``: train the night ISP (a thin command line over TrainConfig).

    python -m day2night.train --train PAIRS/ --val VAL/ -o RUN/ [--epochs 500] [--device cuda]
    python -m day2night.train --fresh DAY_DIR/ --val VAL/ -o RUN/   # fresh synthesis per epoch
    torchrun --nproc-per-node 2 -m day2night.train ...               # data parallel (DDP)

PAIRS/ and VAL/ hold ``<name>_x.npy`` (network input) and ``<name>_y.npy`` (uint8 sRGB
target) pairs (``day2night.train.save_pair``). RUN/ gets last.pt (every epoch; a rerun
resumes from it), best.pt (lowest validation loss) and history.json.
"""

import argparse
import dataclasses
import sys

from ..isos import NOISY_ISOS
from . import data, trainer
from .config import TrainConfig


def parser():
    """The command line: a flag per TrainConfig field (its default, help and choices from
    the field), then the data sets' flags."""
    p = argparse.ArgumentParser(prog="python -m day2night.train", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--train", help="folder of fixed training pairs (<name>_x.npy, <name>_y.npy)")
    src.add_argument("--fresh", metavar="DAY_DIR",
                     help="folder of day DNGs: fresh night synthesis every epoch")
    p.add_argument("--val", required=True, help="folder of fixed validation pairs")
    for f in dataclasses.fields(TrainConfig):
        kw = {k: v for k, v in f.metadata.items() if k != "flags"}
        flags = f.metadata.get("flags") or ("--" + f.name.replace("_", "-"),)
        if f.type in (int, float):
            kw["type"] = f.type
        if f.default is not dataclasses.MISSING:
            kw["default"] = f.default
        p.add_argument(*flags, dest=f.name, **kw)
    p.add_argument("--patch", type=int, default=64, help="training patch side")
    p.add_argument("--crop", type=int, default=512, help="--fresh: synthesis crop side")
    p.add_argument("--crops-per-image", type=int, default=1, help="--fresh: items per image")
    p.add_argument("--task", choices=("noisy", "clean"), default="noisy", help="--fresh: input")
    p.add_argument("--iso", default=",".join(map(str, NOISY_ISOS)), help="--fresh: ISOs drawn from")
    return p


def config(args):
    """The TrainConfig of parsed arguments (:func:`parser`'s)."""
    return TrainConfig(**{f.name: getattr(args, f.name) for f in dataclasses.fields(TrainConfig)})


def main(argv=None):
    try:
        args = parser().parse_args(argv)
    except ImportError as e:
        print(f"day2night.train: error: {e}", file=sys.stderr)
        return 2
    try:
        cfg = config(args)
        if args.train:
            train_set = data.FixedPatches.from_dir(args.train, args.patch, args.patch)
        else:
            isos = tuple(int(i) for i in args.iso.split(",") if i.strip())
            train_set = data.FreshPatches(args.fresh, crop=args.crop, patch=args.patch,
                                          isos=isos, seed=args.seed,
                                          crops_per_image=args.crops_per_image, task=args.task)
        val_set = data.FixedPatches.from_dir(args.val, args.patch, args.patch)
        out = trainer.train(cfg, train_set, val_set)
        trainer.finish()
    except (ValueError, OSError, ImportError) as e:
        print(f"day2night.train: error: {e}", file=sys.stderr)
        return 2
    h = out["history"][-1] if out["history"] else {}
    rank = trainer.dist_info()[0]
    if rank == 0:
        print(f"trained {len(out['history'])} epochs: last loss {h.get('loss', float('nan')):.5f}, "
              f"val PSNR {h.get('val_psnr', float('nan')):.2f} dB; best: {out['best']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
