"""Wall time of the experiment run serially against the same run with ``--ray`` (issue 46,
docs/experiment.md "At the paper's scale"): the miniature data of the tests
(python/tests/experiment_mini.py: 4 day tiles, 6 real scenes), ``--preset mini`` by
default, on a local Ray instance of this machine's CPUs, one CPU per unit (on the 2-core
machine: 2 units at once). The runs alternate, RUNS times (default 3), each into a fresh run
folder; prints each run, the load average before it, the medians and the speed-up, and
whether the two tables are equal (not a test: the tests check that, with one torch thread).

    D2N_BIN=target/release/day2night python benches/experiment_ray.py [RUNS] [-- EXP_ARGS...]

EXP_ARGS replace the default experiment options (``--preset mini --task clean --rows day
ours supervised``: 1 untrained + 2 synthetic + 3 per-fold = 6 units). Needs torch, ray and
the package on PYTHONPATH."""

import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python" / "tests"))
import experiment_mini as mini  # noqa: E402

DEFAULT = ["--preset", "mini", "--task", "clean", "--rows", "day", "ours", "supervised"]


def cli(*args):
    subprocess.run([os.environ.get("D2N_BIN", "day2night"), *map(str, args)], check=True,
                   capture_output=True)


def one(work, day, real, name, args):
    out = work / name
    shutil.rmtree(out, ignore_errors=True)
    load = os.getloadavg()[0]
    t0 = time.monotonic()
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    mini.run_experiment(out, day, real, *args, env=env)
    return time.monotonic() - t0, load, out


def main():
    argv = sys.argv[1:]
    runs = int(argv.pop(0)) if argv and argv[0].isdigit() else 3
    args = argv[argv.index("--") + 1:] if "--" in argv else DEFAULT
    work = pathlib.Path(tempfile.mkdtemp(prefix="d2n-expray-"))
    day = mini.day_dir(work / "days", ROOT / "fixtures" / "day.dng")
    release, _ = mini.bursts(cli, work / "captures", ROOT / "fixtures" / "day.dng")
    real = work / "real"
    cli("real-pairs", release, "-o", real)
    times = {"serial": [], "ray": []}
    same = []
    for r in range(1, runs + 1):
        ts, ls, a = one(work, day, real, "serial", args)
        tr, lr, b = one(work, day, real, "ray", [*args, "--ray"])
        times["serial"].append(ts)
        times["ray"].append(tr)
        same.append((a / "table.json").read_bytes() == (b / "table.json").read_bytes())
        print(f"run {r}: serial {ts:7.1f} s (load {ls:.1f})   --ray {tr:7.1f} s (load {lr:.1f})",
              flush=True)
    ms, mr = statistics.median(times["serial"]), statistics.median(times["ray"])
    print(f"\n{os.cpu_count()} CPUs; experiment options: {' '.join(args)}")
    print("| run | wall s (median) | runs |\n|---|---|---|")
    print(f"| serial | {ms:.1f} | {runs} |\n| --ray (local, 1 CPU per unit) | {mr:.1f} | {runs} |")
    print(f"speed-up {ms / mr:.2f}x; tables equal in {sum(same)} of {runs} run(s)")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
