#!/usr/bin/env python3
"""`day2night dataset` on a Ray cluster: one Ray task per input (its variants' units).

    python ray_dataset.py DAY_DIR -o OUT [--address ADDR] [dataset's options]

The output tree equals `day2night dataset DAY_DIR -o OUT` with the same options: the same
file names, every file byte for byte, the same manifest lines (python/tests/test_ray.py).
A rerun after a kill completes the tree, skipping the units already complete. Each task
reads and decodes its input once for all of its variants (`write_units`), as `dataset` does.

Without --address a new local Ray cluster is started (--num-cpus CPUs); with
`--address auto` or `--address HEAD_IP:6379` (on a node of a cluster made by `ray start`;
Ray 2.60 then wants RAY_AUTH_MODE=token and the cluster's token) the units run on that
cluster's nodes, which must all see DAY_DIR and OUT at the same paths (a shared file
system; see docs/python.md for object storage). Needs `pip install "ray[data]"` beside
day2night.
"""
import argparse
import json
import sys
import time

import ray

import day2night

# dataset's synthesis and output flags: (flag, keyword of write_unit, argparse options).
SYNTH_FLAGS = [
    ("--iso", "iso", {"default": "1600,3200"}),
    ("--mode", "mode", {"default": "local", "choices": ["local", "global", "dimmed", "day"]}),
    ("--relight-formula", "relight_formula", {"default": "release", "choices": ["release", "paper"]}),
    ("--bulbs", "bulbs", {"type": int}),
    ("--lights", "lights", {"type": int}),
    ("--illuminants", "illuminants", {}),
    ("--covariance", "covariance", {"default": "unbiased", "choices": ["unbiased", "ml"]}),
    ("--brightness", "brightness", {}),
    ("--noise-model", "noise_model", {}),
    ("--day-neutral", "day_neutral", {}),
    ("--mask-eval", "mask_eval", {"default": "separable"}),
    ("--target", "target", {"default": "exr", "choices": ["exr", "png", "both", "none"]}),
    ("--input-exr", "input_exr", {"action": "store_true"}),
    ("--compression", "compression", {"default": "none", "choices": ["none", "ljpeg"]}),
    ("--exr-compression", "exr_compression", {"default": "zip"}),
    ("--exr-zip-level", "exr_zip_level", {"type": int, "default": 1}),
    ("--truncate", "truncate", {"action": "store_true"}),
    ("--compat", "compat", {"choices": ["release"]}),
]


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("day_dir", metavar="DAY_DIR")
    ap.add_argument("-o", "--output", "--out", dest="out", required=True, metavar="OUT")
    ap.add_argument("--address", help="Ray cluster address (default: start a local cluster)")
    ap.add_argument("--num-cpus", type=int, help="CPUs of the local cluster (default: all)")
    ap.add_argument("--cpus-per-task", type=int, default=1,
                    help="CPUs reserved per task (one input); also its synthesis threads "
                         "(default 1)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variants", type=int, default=1)
    split = ap.add_mutually_exclusive_group()
    split.add_argument("--val", type=int)
    split.add_argument("--val-fraction", type=float)
    ap.add_argument("--shard", metavar="I/N")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--wait", action="store_true")
    ap.add_argument("--quiet", "-q", action="store_true")
    for flag, _, kw in SYNTH_FLAGS:
        ap.add_argument(flag, **kw)
    return ap.parse_args(argv)


def input_writer(out, threads, overwrite, wait, options):
    """The Ray task body: write the units of one input (its variants; the input is decoded
    once), return their manifest records (as JSON text, so Ray's Arrow blocks need no
    schema for them) and why each was computed ("" when skipped)."""

    def write(item):
        day2night.set_threads(threads)
        done = day2night.write_units(json.loads(item["units"]), out, overwrite=overwrite,
                                     wait=wait, reason=True, **options)
        return {"records": json.dumps([[record, reason or ""] for record, reason in done])}

    return write


def main(argv=None):
    a = parse_args(argv)
    options = {kw: getattr(a, kw) for _, kw, _ in SYNTH_FLAGS}
    options = {k: v for k, v in options.items() if v is not None}
    t0 = time.time()
    # The units (and the resume state) are decided here, on the driver, as `dataset` does.
    try:
        units = day2night.dataset_units(a.day_dir, a.out, variants=a.variants, val=a.val,
                                        val_fraction=a.val_fraction, seed=a.seed,
                                        shard=a.shard, overwrite=a.overwrite)
    except (OSError, ValueError) as e:
        print(f"ray_dataset: {e}", file=sys.stderr)
        return 2
    if a.address:
        ray.init(address=a.address, log_to_driver=not a.quiet)
    else:
        # address="local": always a new local cluster (never one `ray start` left behind).
        ray.init(address="local", num_cpus=a.num_cpus, include_dashboard=False,
                 log_to_driver=not a.quiet)
    ctx = ray.data.DataContext.get_current()
    ctx.enable_progress_bars = not a.quiet
    work = input_writer(a.out, a.cpus_per_task, a.overwrite, a.wait, options)
    groups = [{"units": json.dumps(g)} for g in day2night.group_units(units)]
    rows = (ray.data.from_items(groups, override_num_blocks=max(1, len(groups)))
            .map(work, num_cpus=a.cpus_per_task)
            .take_all())
    done = [pair for r in rows for pair in json.loads(r["records"])]
    records = [record for record, _ in done]
    path = day2night.write_manifest(records, a.out, shard=a.shard)
    failed = [r for r in records if r["status"] != "ok"]
    skipped = sum(1 for _, reason in done if not reason)
    print(f"ray_dataset: {len(records)} units: {len(records) - skipped - len(failed)} computed, "
          f"{skipped} skipped (up to date), {len(failed)} failed; manifest {path}; "
          f"{time.time() - t0:.1f} s", file=sys.stderr)
    for r in failed:
        print(f"ray_dataset: FAILED {r['input']} variant {r['variant']}: {r.get('error')}",
              file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
