#!/usr/bin/env bash
# Whole-program benchmark of issue 7 (not a test; CI needs nothing from it).
#
#   benches/run.sh                 # 5 runs per configuration
#   RUNS=9 benches/run.sh          # more runs
#   DATASET=1 benches/run.sh       # also (d): `dataset` on 20 such images, --jobs 2
#                                  # (DATASET_RUNS runs, default 3)
#   SKIP_RUNS=1 WORK=DIR benches/run.sh  # reprint the table from DIR's recorded times
#   D2N_BIN=/path/to/old/day2night benches/run.sh  # time another build (before/after)
#   WORK=/tmp/d2n-bench benches/run.sh   # scratch directory (default: a fresh mktemp -d)
#   REF_CMD='...' REF_RUNS=3 benches/run.sh  # also time the authors' release in this run
#
# Builds release, generates a deterministic 12 MP 10-bit RGGB day DNG (4032x3024, black 64,
# white 1023) with examples/make_bench_input.rs, then times with GNU time (wall, peak RSS):
#   (a) synth --target both --jobs 2 (clean DNG, ISO 1600 + 3200 DNGs, EXR, PNG, sidecar)
#   (b) the same with --jobs 1
#   (c) the I/O floor: examples/io_floor.rs reads the input and writes files of the same
#       number and sizes as (a) through the same atomic output path, no computation
#   (d) optional (DATASET=1): dataset on 20 copies of the input, --jobs 2
#   (r) optional (REF_CMD set): the reference, a shell command run with `bash -c` REF_RUNS
#       times (default 3), interleaved with (a): one (a) run, then one (r) run, and so on.
#       It sees REF_IN (the input DNG) and REF_OUT (an output directory, emptied before each
#       run) in its environment; its output goes to $WORK/refcmd.log. The speed-up column then
#       divides (r)'s measured median by each row's median. Without REF_CMD it divides the
#       issue-7 constant (29.2 s, 3.0 GB), which was not measured in this run.
#       docs/benchmarks.md says how to set up the authors' release for REF_CMD.
# Needs GNU time (/usr/bin/time; Debian package `time`).
set -euo pipefail

RUNS=${RUNS:-5}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
REF_WALL=29.2   # authors' release, s (issue 7 constant; used only when REF_CMD is not set)
REF_RSS_MB=3000 # authors' release, MB (issue 7 constant; used only when REF_CMD is not set)
REF_RUNS=${REF_RUNS:-3}

if [ ! -x /usr/bin/time ]; then
    echo "benches/run.sh: GNU time missing: apt-get install -y time" >&2
    exit 1
fi

cd "$ROOT"
cargo build --release --quiet --bin day2night --example make_bench_input --example io_floor
BIN=${D2N_BIN:-$CARGO_TARGET_DIR/release/day2night}
GEN=$CARGO_TARGET_DIR/release/examples/make_bench_input
FLOOR=$CARGO_TARGET_DIR/release/examples/io_floor

WORK=${WORK:-$(mktemp -d -t d2n-bench.XXXXXX)}
mkdir -p "$WORK"
IN=$WORK/day.dng
[ -f "$IN" ] || "$GEN" "$IN"

# time_one NAME CMD...: runs CMD once (after a clean of $WORK/out), appends
# "wall_s rss_kb user_s sys_s" to $WORK/NAME.times
time_one() {
    local name=$1
    shift
    rm -rf "$WORK/out"
    /usr/bin/time -f "%e %M %U %S" -o "$WORK/$name.one" "$@" >/dev/null
    cat "$WORK/$name.one" >>"$WORK/$name.times"
}

# time_runs NAME RUNS CMD...: runs CMD RUNS times, records them in $WORK/NAME.times
time_runs() {
    local name=$1 runs=$2
    shift 2
    : >"$WORK/$name.times"
    for _ in $(seq "$runs"); do
        time_one "$name" "$@"
    done
}

# time_ref: one run of the reference command (r), output in $WORK/refcmd.log
time_ref() {
    rm -rf "$REF_OUT"
    mkdir -p "$REF_OUT"
    if ! /usr/bin/time -f "%e %M %U %S" -o "$WORK/refcmd.one" bash -c "$REF_CMD" >>"$WORK/refcmd.log" 2>&1; then
        echo "benches/run.sh: REF_CMD failed; its output is in $WORK/refcmd.log" >&2
        exit 1
    fi
    cat "$WORK/refcmd.one" >>"$WORK/refcmd.times"
}

# reference output directory for the I/O floor (one untimed run of (a))
[ "${SKIP_RUNS:-0}" = 1 ] || rm -rf "$WORK/ref"
[ -d "$WORK/ref" ] || "$BIN" synth "$IN" -o "$WORK/ref" --target both --jobs 2 --seed 1

if [ "${SKIP_RUNS:-0}" != 1 ]; then
    if [ -n "${REF_CMD:-}" ]; then
        # (a) interleaved with (r), so that both see the same machine load
        export REF_IN=$IN REF_OUT=$WORK/refcmd_out
        : >"$WORK/synth_j2.times"
        : >"$WORK/refcmd.times"
        : >"$WORK/refcmd.log"
        n=$((RUNS > REF_RUNS ? RUNS : REF_RUNS))
        for i in $(seq "$n"); do
            [ "$i" -gt "$RUNS" ] || time_one synth_j2 "$BIN" synth "$IN" -o "$WORK/out" --target both --jobs 2 --seed 1
            [ "$i" -gt "$REF_RUNS" ] || time_ref
        done
        rm -rf "$REF_OUT"
    else
        rm -f "$WORK/refcmd.times"
        time_runs synth_j2 "$RUNS" "$BIN" synth "$IN" -o "$WORK/out" --target both --jobs 2 --seed 1
    fi
fi
[ "${SKIP_RUNS:-0}" = 1 ] || time_runs synth_j1 "$RUNS" "$BIN" synth "$IN" -o "$WORK/out" --target both --jobs 1 --seed 1
[ "${SKIP_RUNS:-0}" = 1 ] || time_runs io_floor "$RUNS" "$FLOOR" "$IN" "$WORK/ref" "$WORK/out"

if [ "${DATASET:-0}" = 1 ] && [ "${SKIP_RUNS:-0}" != 1 ]; then
    mkdir -p "$WORK/days"
    for i in $(seq -w 1 20); do
        [ -e "$WORK/days/day$i.dng" ] || cp "$IN" "$WORK/days/day$i.dng"
    done
    time_runs dataset "${DATASET_RUNS:-3}" "$BIN" dataset "$WORK/days" -o "$WORK/out" --jobs 2 --quiet \
        --target both --seed 1
fi

# stats FILE -> "median min max medianRSS_MB maxRSS_MB"
stats() {
    local w r c
    w=$(cut -d' ' -f1 "$1" | sort -g | tr '\n' ' ')
    r=$(cut -d' ' -f2 "$1" | sort -g | tr '\n' ' ')
    c=$(awk '{print $3 + $4}' "$1" | sort -g | tr '\n' ' ')
    echo "$w|$r|$c" | awk -F'|' '{
        n=split($1, w, " "); m=split($2, r, " "); k=split($3, c, " ");
        med = (n%2) ? w[(n+1)/2] : (w[n/2]+w[n/2+1])/2;
        rmed = (m%2) ? r[(m+1)/2] : (r[m/2]+r[m/2+1])/2;
        cmed = (k%2) ? c[(k+1)/2] : (c[k/2]+c[k/2+1])/2;
        printf "%.3f %.3f %.3f %.0f %.0f %.2f", med, w[1], w[n], rmed/1024, r[m]/1024, cmed }'
}

read -r floor_med _ <<<"$(stats "$WORK/io_floor.times")"
if [ -s "$WORK/refcmd.times" ]; then
    read -r ref_med _ _ _ ref_rss _ <<<"$(stats "$WORK/refcmd.times")"
    ref_note="authors' release measured in this run (r): median ${ref_med} s, ${ref_rss} MB peak"
    ref_runs=$(wc -l <"$WORK/refcmd.times")
else
    ref_med=$REF_WALL
    ref_rss=$REF_RSS_MB
    ref_note="authors' release ${REF_WALL} s, ${REF_RSS_MB} MB peak: issue 7 constant, not measured in this run"
fi
echo
echo "machine: $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p' | head -1)," \
    "$(free -g | awk '/^Mem:/{print $2}') GiB; load: $(cut -d' ' -f1-3 /proc/loadavg);" \
    "runs: $RUNS${ref_runs:+ (reference: $ref_runs)}"
printf "%-34s %8s %8s %8s %9s %7s %9s %9s\n" configuration "median_s" "min_s" "max_s" \
    "peakRSS_MB" "cpu_s" "vs_ref" "vs_floor"
row() {
    local label=$1 file=$2
    read -r med mn mx _ rss cpu <<<"$(stats "$file")"
    printf "%-34s %8s %8s %8s %9s %7s %8.1fx %8.2fx\n" "$label" "$med" "$mn" "$mx" "$rss" "$cpu" \
        "$(echo "$ref_med / $med" | bc -l)" "$(echo "$med / $floor_med" | bc -l)"
}
row "(a) synth --target both --jobs 2" "$WORK/synth_j2.times"
row "(b) synth --target both --jobs 1" "$WORK/synth_j1.times"
row "(c) I/O floor" "$WORK/io_floor.times"
if [ "${DATASET:-0}" = 1 ]; then
    read -r med mn mx _ rss cpu <<<"$(stats "$WORK/dataset.times")"
    printf "%-34s %8s %8s %8s %9s %7s   %s images/s (median)\n" "(d) dataset 20 images --jobs 2" \
        "$med" "$mn" "$mx" "$rss" "$cpu" "$(echo "20 / $med" | bc -l | xargs printf %.2f)"
fi
[ ! -s "$WORK/refcmd.times" ] || row "(r) reference (REF_CMD)" "$WORK/refcmd.times"
echo "reference: $ref_note;" \
    "vs_ref = reference median / row median (speed-up, higher is better)," \
    "vs_floor = run time / I/O floor, cpu_s = median user+system CPU time"
if [ -s "$WORK/refcmd.times" ]; then
    read -r _ _ _ _ a_rss _ <<<"$(stats "$WORK/synth_j2.times")"
    echo "peak RSS: (r) / (a) = $(echo "$ref_rss / $a_rss" | bc -l | xargs printf %.1f)x;" \
        "REF_CMD: ${REF_CMD:-(not set: times reprinted from $WORK/refcmd.times)}"
fi
echo "raw times (wall_s rss_kb user_s sys_s per run): $WORK/*.times"
