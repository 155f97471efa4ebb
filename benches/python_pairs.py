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
"""
import argparse
import os
import platform
import statistics
import threading
import time

import day2night
from day2night import NightPairs


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
    a = ap.parse_args()
    raw = day2night.read_dng(a.dng)
    day2night.synthesize(raw, isos=(1600,), crop=(0, 0, a.crop, a.crop))  # warm up
    rows = []
    day2night.set_threads(0)
    rows.append(("crops, 1 Python thread (pool: all cores)",
                 [crops_per_s(raw, a.pairs, 1, a.crop) for _ in range(a.runs)]))
    day2night.set_threads(1)
    rows.append(("crops, 1 Python thread x 1 worker",
                 [crops_per_s(raw, a.pairs, 1, a.crop) for _ in range(a.runs)]))
    rows.append(("crops, 2 Python threads x 1 worker",
                 [crops_per_s(raw, a.pairs, 2, a.crop) for _ in range(a.runs)]))
    day2night.set_threads(0)
    d = os.path.dirname(os.path.abspath(a.dng))
    ds = NightPairs(d, crop=a.crop, isos=(1600,), crops_per_image=a.pairs)
    ds._cache[os.path.basename(a.dng)] = raw
    ds.files = [os.path.basename(a.dng)]

    def items():
        t0 = time.perf_counter()
        for i in range(a.pairs):
            ds[i]
        return a.pairs / (time.perf_counter() - t0)

    rows.append(("NightPairs items, 1 thread", [items() for _ in range(a.runs)]))

    def whole():
        t0 = time.perf_counter()
        for k in range(3):
            day2night.synthesize(raw, seed=1, variant=k, isos=(1600,))
        return 3 / (time.perf_counter() - t0)

    rows.append(("whole frame (12 MP), 1 thread", [whole() for _ in range(a.runs)]))
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else "?"
    print(f"machine: {os.cpu_count()} cores, {cpu}; python {platform.python_version()}; "
          f"load {' '.join(load)}; input {raw.data.shape[1]}x{raw.data.shape[0]}; "
          f"crop {a.crop}; runs {a.runs}")
    print(f"{'configuration':44} {'median pairs/s':>15} {'min':>8} {'max':>8}")
    for name, v in rows:
        print(f"{name:44} {statistics.median(v):15.1f} {min(v):8.1f} {max(v):8.1f}")
    base = statistics.median(rows[-1][1])
    print(f"crops vs whole frame: {statistics.median(rows[0][1]) / base:.0f}x pairs/s")


if __name__ == "__main__":
    main()
