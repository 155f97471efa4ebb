#!/usr/bin/env python3
"""Python package throughput (issue 12): 512x512 training pairs per second from a 12 MP day
DNG held in memory, against whole-frame synthesis. Not a test; prints a table.

    benches/python.sh                       # builds the package into .venv, makes the input
    .venv/bin/python benches/python_pairs.py DAY.dng [--runs 5] [--pairs 200]

Rows (one ISO, linear target, each a median of --runs runs):
  crops, 1 Python thread    synthesize(crop=512x512), the thread's pool has all cores
  crops, 1 x 1 worker       one thread with one rayon worker (set_threads(1))
  crops, 2 Python threads   two threads, each with one rayon worker: the GIL-release gain
  NightPairs items          the dataset's __getitem__ (crop + packing), one thread
  whole frame               synthesize() without a crop: the full 12 MP clean + noisy + target

Then the loader's overhead (issue 19): the same --pairs crops (NightPairs' own placements,
one ISO, linear target) timed as a bare synthesize(raw, crop=...), as the item before issue
19 (synthesize, then pack_bayer in numpy and a CHW copy) and as a NightPairs item (one Rust
call that returns the arrays in their final layout), the three interleaved in each of
--runs rounds (order rotated); the ratios are medians of the per-round ratios.
"""
import argparse
import os
import platform
import statistics
import threading
import time

import numpy as np

import day2night
from day2night import NightPairs, pack_bayer


def crops_per_s(raw, n, threads, crop):
    h, w = raw.meta["default_crop"][2:]
    positions = [((2 * ((i * 7919) % ((h - crop) // 2))), 2 * ((i * 104729) % ((w - crop) // 2)))
                 for i in range(n)]

    def work(part):
        for k, (t, l) in enumerate(part):
            day2night.synthesize(raw, seed=1, variant=k, isos=(1600,), crop=(t, l, crop, crop))

    parts = [positions[i::threads] for i in range(threads)]
    ts = [threading.Thread(target=work, args=(p,)) for p in parts]
    t0 = time.perf_counter()
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return n / (time.perf_counter() - t0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dng")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--pairs", type=int, default=200)
    ap.add_argument("--crop", type=int, default=512)
    ap.add_argument("--overhead-only", action="store_true",
                    help="only the loader-overhead comparison (bare vs items)")
    ap.add_argument("--threads", type=int, default=0,
                    help="worker threads of the overhead comparison (0: all cores; 1: as a "
                         "DataLoader worker with set_threads(1))")
    a = ap.parse_args()
    load0 = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else "?"
    raw = day2night.read_dng(a.dng)
    day2night.synthesize(raw, isos=(1600,), crop=(0, 0, a.crop, a.crop))  # warm up
    rows = []
    d = os.path.dirname(os.path.abspath(a.dng))
    ds = NightPairs(d, crop=a.crop, isos=(1600,), crops_per_image=a.pairs)
    ds.files = [os.path.basename(a.dng)]
    ds.preload()  # decoded once, before any timing

    def items():
        t0 = time.perf_counter()
        for i in range(a.pairs):
            ds[i]
        return a.pairs / (time.perf_counter() - t0)

    def whole():
        t0 = time.perf_counter()
        for k in range(3):
            day2night.synthesize(raw, seed=1, variant=k, isos=(1600,))
        return 3 / (time.perf_counter() - t0)

    if not a.overhead_only:
        day2night.set_threads(0)
        rows.append(("crops, 1 Python thread (pool: all cores)",
                     [crops_per_s(raw, a.pairs, 1, a.crop) for _ in range(a.runs)]))
        day2night.set_threads(1)
        rows.append(("crops, 1 Python thread x 1 worker",
                     [crops_per_s(raw, a.pairs, 1, a.crop) for _ in range(a.runs)]))
        rows.append(("crops, 2 Python threads x 1 worker",
                     [crops_per_s(raw, a.pairs, 2, a.crop) for _ in range(a.runs)]))
        day2night.set_threads(0)
        rows.append(("NightPairs items, 1 thread", [items() for _ in range(a.runs)]))
        rows.append(("whole frame (12 MP), 1 thread", [whole() for _ in range(a.runs)]))
    day2night.set_threads(a.threads)
    # The loader's overhead: bare synthesize vs items (before and after issue 19), same crops.
    places = [ds.place(i) for i in range(a.pairs)]

    def bare():
        t0 = time.perf_counter()
        for q in places:
            day2night.synthesize(raw, seed=ds.seed, variant=q["variant"], isos=(q["iso"],),
                                 crop=q["crop"])
        return (time.perf_counter() - t0) / a.pairs

    def item_before():
        # NightPairs.__getitem__ before issue 19: the dict of synthesize, packed in numpy.
        t0 = time.perf_counter()
        for i, q in enumerate(places):
            ds.params(i)
            meta = raw.meta
            top, left = q["crop"][:2]
            out = day2night.synthesize(raw, seed=ds.seed, variant=q["variant"],
                                       isos=(q["iso"],), target="linear", crop=q["crop"])
            {"noisy": pack_bayer(out["noisy"][q["iso"]], meta, top, left),
             "clean": pack_bayer(out["clean"], meta, top, left),
             "target": np.ascontiguousarray(out["target"].transpose(2, 0, 1)),
             "origin": np.array([top, left], dtype=np.int64)}
        return (time.perf_counter() - t0) / a.pairs

    def item_now():
        t0 = time.perf_counter()
        for i in range(a.pairs):
            ds[i]
        return (time.perf_counter() - t0) / a.pairs

    fns = [("bare synthesize(crop)", bare), ("item before (numpy packing)", item_before),
           ("NightPairs item (Rust layout)", item_now)]
    times = {name: [] for name, _ in fns}
    for r in range(a.runs):
        for name, fn in fns[r % 3:] + fns[:r % 3]:
            times[name].append(fn())
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    print(f"machine: {os.cpu_count()} cores, {cpu}; python {platform.python_version()}; "
          f"load before {' '.join(load0)}; input {raw.data.shape[1]}x{raw.data.shape[0]}; "
          f"crop {a.crop}; runs {a.runs}")
    if rows:
        print(f"{'configuration':44} {'median pairs/s':>15} {'min':>8} {'max':>8}")
        for name, v in rows:
            print(f"{name:44} {statistics.median(v):15.1f} {min(v):8.1f} {max(v):8.1f}")
        base = statistics.median(rows[-1][1])
        print(f"crops vs whole frame: {statistics.median(rows[0][1]) / base:.0f}x pairs/s")
    print(f"\nloader overhead, {a.pairs} crops of {a.crop}x{a.crop}, one ISO, linear target, "
          f"interleaved, {a.runs} rounds, set_threads({a.threads})")
    print(f"{'per pair':44} {'median ms':>10} {'vs bare (median of rounds)':>28}")
    b = times["bare synthesize(crop)"]
    for name, _ in fns:
        v = times[name]
        ratio = statistics.median(x / y for x, y in zip(v, b))
        print(f"{name:44} {1e3 * statistics.median(v):10.2f} {ratio:27.3f}x")
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else "?"
    print(f"load after: {' '.join(load)}")


if __name__ == "__main__":
    main()
