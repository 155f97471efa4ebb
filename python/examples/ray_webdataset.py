#!/usr/bin/env python3
"""Training pairs as WebDataset shards, made on Ray: `NightPairs` items (fresh night pairs
on random crops of the day DNGs, the arrays a DataLoader would get) written by Ray Data's
`write_webdataset` straight from memory, to a folder or to object storage.

    python ray_webdataset.py DAY_DIR -o URI [--address ADDR] [--crop 512]
        [--iso 1600,3200] [--seed 0] [--epoch 0] [--crops-per-image 8]
        [--items-per-shard 256] [--workers N]

URI is a local folder or a URI pyarrow opens (s3://bucket/prefix, gs://bucket/prefix; the
credentials are the environment's, as for any pyarrow filesystem). Each sample is
`<name>_e<epoch>_<index>.{noisy.npy,clean.npy,target.npy,json}`: noisy and clean packed
Bayer crops (4 x crop/2 x crop/2 float32), the target (3 x crop x crop float32, linear
Rec.709) and the item's iso, variant, origin, name, seed, epoch and index. Item i of epoch e
is the same as `NightPairs(DAY_DIR, ..., seed=S)[i]` after `set_epoch(e)`, on any worker:
one epoch per run, `--epoch` for the next. Needs `pip install "ray[data]"`.
"""
import argparse
import sys

import ray

import day2night
from day2night import NightPairs


class Items:
    """A Ray actor per worker: its own NightPairs, so decoded images stay cached there."""

    def __init__(self, day_dir, crop, isos, seed, crops_per_image, epoch, threads):
        day2night.set_threads(threads)
        self.ds = NightPairs(day_dir, crop=crop, isos=isos, seed=seed,
                             crops_per_image=crops_per_image)
        self.ds.set_epoch(epoch)
        self.seed, self.epoch = seed, epoch

    def __call__(self, row):
        i = int(row["id"])
        it = self.ds[i]
        return {
            "__key__": f"{it['name']}_e{self.epoch}_{i:08d}",
            "noisy.npy": it["noisy"],
            "clean.npy": it["clean"],
            "target.npy": it["target"],
            "json": {"iso": int(it["iso"]), "variant": int(it["variant"]),
                     "origin": [int(x) for x in it["origin"]], "name": it["name"],
                     "seed": self.seed, "epoch": self.epoch, "index": i},
        }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("day_dir", metavar="DAY_DIR")
    ap.add_argument("-o", "--output", dest="out", required=True, metavar="URI")
    ap.add_argument("--address", help="Ray cluster address (default: start a local cluster)")
    ap.add_argument("--num-cpus", type=int, help="CPUs of the local cluster (default: all)")
    ap.add_argument("--workers", type=int, default=2, help="Ray actors making items")
    ap.add_argument("--cpus-per-worker", type=int, default=1)
    ap.add_argument("--crop", type=int, default=512)
    ap.add_argument("--iso", default="1600,3200")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--epoch", type=int, default=0)
    ap.add_argument("--crops-per-image", type=int, default=8)
    ap.add_argument("--items-per-shard", type=int, default=256)
    ap.add_argument("--quiet", "-q", action="store_true")
    a = ap.parse_args(argv)
    isos = tuple(int(x) for x in a.iso.split(","))
    n = len(NightPairs(a.day_dir, crop=a.crop, isos=isos, seed=a.seed,
                       crops_per_image=a.crops_per_image))
    if a.address:
        ray.init(address=a.address, log_to_driver=not a.quiet)
    else:
        # address="local": always a new local cluster (never one `ray start` left behind).
        ray.init(address="local", num_cpus=a.num_cpus, include_dashboard=False,
                 log_to_driver=not a.quiet)
    ray.data.DataContext.get_current().enable_progress_bars = not a.quiet
    (ray.data.range(n)
     .map(Items, fn_constructor_args=(a.day_dir, a.crop, isos, a.seed, a.crops_per_image,
                                      a.epoch, a.cpus_per_worker),
          concurrency=a.workers, num_cpus=a.cpus_per_worker)
     .write_webdataset(a.out, min_rows_per_file=a.items_per_shard))
    print(f"ray_webdataset: {n} pairs of epoch {a.epoch} written to {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
