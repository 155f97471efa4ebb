"""The Python benchmark scripts under benches/ still run against the package (a smoke run
at a tiny size, not a measurement): benches/python_pairs.py once stopped with an
AttributeError after a refactor of `NightPairs`, and nothing noticed for a stop."""

import json
import os
import subprocess
import sys

from conftest import ROOT, need_torch

DAY = ROOT / "fixtures" / "day.dng"


def run_bench(*args):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    r = subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                       env=env, timeout=600)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_python_pairs_bench_runs_tiny():
    out = run_bench(ROOT / "benches" / "python_pairs.py", DAY, "--runs", "1", "--pairs", "2",
                    "--crop", "64")
    rows = {line.split("  ")[0].strip(): line for line in out.splitlines() if "  " in line}
    for name in ("crops, 2 Python threads x 1 worker", "NightPairs items, 1 thread",
                 "NightPairs item (Rust layout)"):
        assert name in rows, out
        # each row ends in positive figures (pairs/s or ms per pair)
        assert float(rows[name].split()[-1].rstrip("x")) > 0, rows[name]


def test_train_bench_fresh_runs_tiny():
    need_torch()
    out = run_bench(ROOT / "benches" / "train_bench.py", "fresh", DAY, "--items", "2",
                    "--runs", "1", "--train-steps", "0", "--crop", "128")
    res = json.loads(out)
    assert res["bench"] == "fresh" and res["crop"] == 128 and res["images"] == 1
    assert res["patches_per_s_per_core"] > 0 and res["patches_per_cpu_s"] > 0
    assert all(v > 0 for v in res["numpy_path"]["stage_ms"].values()), res["numpy_path"]
