#!/usr/bin/env bash
# CPU time of python/examples/ray_dataset.py against `day2night dataset` on the same tree
# (issue 26, docs/dataset.md "Ray Data, or another scheduler"): four 12 MP lossless-JPEG day
# DNGs (examples/make_bench_input.rs, `convert --compression ljpeg`), --variants 3, default
# options; `dataset --jobs 2` and Ray on a local 2-CPU cluster, one CPU per task. BEFORE=FILE
# adds a second Ray example (e.g. the one task per unit version:
# `git show eb28fa1:python/examples/ray_dataset.py > /tmp/before.py`). Runs interleaved,
# RUNS times (default 3); prints each run and the medians. CPU is measured by
# benches/cputime.py (a cpuacct cgroup: root). Needs ray[data] and the package in $D2N_VENV.
#   D2N_VENV=/path/venv [BEFORE=old_example.py] [RUNS=3] benches/ray_cpu.sh
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
PY="${D2N_VENV:-$ROOT/.venv}/bin/python"
RUNS=${RUNS:-3}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target} RAY_USAGE_STATS_ENABLED=0
cargo build --release --quiet --bin day2night --example make_bench_input
BIN="$CARGO_TARGET_DIR/release/day2night"
WORK=${WORK:-$(mktemp -d -t d2n-raycpu.XXXXXX)}
mkdir -p "$WORK/days"
[ -f "$WORK/base.dng" ] || "$CARGO_TARGET_DIR/release/examples/make_bench_input" "$WORK/base.dng"
for i in 1 2 3 4; do
  [ -f "$WORK/days/in$i.dng" ] || "$BIN" convert "$WORK/base.dng" "$WORK/days/in$i.dng" --compression ljpeg
done
configs="cli after"
[ -n "${BEFORE:-}" ] && configs="cli before after"
for r in $(seq "$RUNS"); do
  for cfg in $configs; do
    out="$WORK/out_$cfg"
    rm -rf "$out"
    echo "$cfg run $r: $(uptime)" >&2
    case $cfg in
      cli) cmd=("$BIN" dataset "$WORK/days" -o "$out" --variants 3 --jobs 2 --quiet) ;;
      before) cmd=("$PY" "$BEFORE" "$WORK/days" -o "$out" --variants 3 --num-cpus 2 --quiet) ;;
      after) cmd=("$PY" python/examples/ray_dataset.py "$WORK/days" -o "$out" --variants 3 --num-cpus 2 --quiet) ;;
    esac
    "$PY" benches/cputime.py "$WORK/t_${cfg}_$r.json" "${cmd[@]}" 2>>"$WORK/log"
  done
  [ "$cfg" = cli ] || diff -r "$WORK/out_cli" "$WORK/out_after" >/dev/null || { echo "trees differ" >&2; exit 1; }
done
"$PY" - "$WORK" $configs <<'PYEOF'
import json, statistics, sys
work, configs = sys.argv[1], sys.argv[2:]
for cfg in configs:
    runs = [json.load(open(f"{work}/t_{cfg}_{r}.json")) for r in range(1, 100)
            if __import__("os").path.exists(f"{work}/t_{cfg}_{r}.json")]
    cpu = [x["cpu"] for x in runs]
    wall = [x["wall"] for x in runs]
    print(f"{cfg:7s} CPU s {statistics.median(cpu):6.2f} ({min(cpu):.2f}-{max(cpu):.2f})"
          f"  wall s {statistics.median(wall):5.1f}  runs {len(runs)}")
PYEOF
