"""``python -m day2night.train``: train the night ISP (a thin command line over TrainConfig).

    python -m day2night.train --train PAIRS/ --val VAL/ -o RUN/ [--epochs 500] [--device cuda]
    python -m day2night.train --fresh DAY_DIR/ --val VAL/ -o RUN/   # fresh synthesis per epoch
    torchrun --nproc-per-node 2 -m day2night.train ...               # data parallel (DDP)

PAIRS/ and VAL/ hold ``<name>_x.npy`` (network input) and ``<name>_y.npy`` (uint8 sRGB
target) pairs (``day2night.train.save_pair``). RUN/ gets last.pt (every epoch; a rerun
resumes from it), best.pt (lowest validation loss) and history.json.
"""

import argparse
import sys

from ..isos import NOISY_ISOS


def parser():
    p = argparse.ArgumentParser(prog="python -m day2night.train", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--train", help="folder of fixed training pairs (<name>_x.npy, <name>_y.npy)")
    src.add_argument("--fresh", metavar="DAY_DIR",
                     help="folder of day DNGs: fresh night synthesis every epoch")
    p.add_argument("--val", required=True, help="folder of fixed validation pairs")
    p.add_argument("-o", "--out", required=True, help="run folder (checkpoints, history)")
    p.add_argument("--epochs", type=int, default=500)
    p.add_argument("--batch-size", type=int, default=128, help="patches per step (global)")
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--decay-at", type=float, default=0.8,
                   help="fraction of the epochs after which the rate is x0.1")
    p.add_argument("--init-features", type=int, default=32, help="UNet width (32 in the paper)")
    p.add_argument("--patch", type=int, default=64)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--device", default="cpu", help="cpu or cuda")
    p.add_argument("--workers", type=int, default=0, help="DataLoader worker processes")
    p.add_argument("--amp", choices=["bf16"], help="bfloat16 mixed precision (for GPUs)")
    p.add_argument("--channels-last", action="store_true",
                   help="channels-last memory format (for GPUs)")
    p.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    p.add_argument("--record-shards", action="store_true",
                   help="write each rank's sample indices to OUT/shards/ (checks)")
    p.add_argument("--crop", type=int, default=512, help="--fresh: synthesis crop side")
    p.add_argument("--crops-per-image", type=int, default=1, help="--fresh: items per image")
    p.add_argument("--task", choices=("noisy", "clean"), default="noisy", help="--fresh: input")
    p.add_argument("--iso", default=",".join(map(str, NOISY_ISOS)), help="--fresh: ISOs drawn from")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        from . import data, trainer
        cfg = trainer.TrainConfig(
            out_dir=args.out, epochs=args.epochs, batch_size=args.batch_size, lr=args.lr,
            decay_at=args.decay_at, init_features=args.init_features, seed=args.seed,
            device=args.device, workers=args.workers, progress=not args.no_progress,
            record_shards=args.record_shards, amp=args.amp, channels_last=args.channels_last)
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
