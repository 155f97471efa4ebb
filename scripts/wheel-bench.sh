#!/usr/bin/env bash
# The numbers of docs/benchmarks.md, "Packaging": the wheel's size, its installed size,
# and the start-up time of `day2night --version` (median of 10, interleaved) from the
# wheel's command, from a cargo-built binary, and through a Python console-script-like
# shim that execs the binary (the alternative the wheel does not take, docs/release.md).
#   scripts/wheel-bench.sh WHEEL CARGO_BIN
set -euo pipefail
wheel="$(realpath "${1:?usage: scripts/wheel-bench.sh WHEEL CARGO_BIN}")"
cargo_bin="$(realpath "${2:?usage: scripts/wheel-bench.sh WHEEL CARGO_BIN}")"
py="${D2N_WHEEL_PYTHON:-$(command -v python3)}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$py" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$wheel"
site=$("$work/venv/bin/python" -c "import day2night, os; print(os.path.dirname(day2night.__file__))")
echo "wheel: $(basename "$wheel") $(stat -c %s "$wheel") bytes"
echo "installed: package $(du -sb "$site" | cut -f1) bytes + command $(stat -c %s "$work/venv/bin/day2night") bytes"
echo "cargo binary: $(stat -c %s "$cargo_bin") bytes"
cat > "$work/shim.py" <<PY
import os, sys
os.execv("$work/venv/bin/day2night", ["day2night"] + sys.argv[1:])
PY
"$work/venv/bin/python" - "$work/venv/bin/day2night" "$cargo_bin" "$work/venv/bin/python" "$work/shim.py" <<'PY'
import statistics, subprocess, sys, time
wheel_cmd, cargo_bin, py, shim = sys.argv[1:]
runs = {"wheel command": [wheel_cmd], "cargo binary": [cargo_bin], "python shim": [py, shim]}
times = {k: [] for k in runs}
for _ in range(10):
    for name, argv in runs.items():
        t = time.perf_counter()
        subprocess.run(argv + ["--version"], check=True, stdout=subprocess.DEVNULL)
        times[name].append(time.perf_counter() - t)
for name, ts in times.items():
    print(f"{name}: day2night --version median {statistics.median(ts) * 1000:.1f} ms "
          f"(min {min(ts) * 1000:.1f}, max {max(ts) * 1000:.1f}, 10 runs)")
PY
