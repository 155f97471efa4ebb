#!/usr/bin/env bash
# Side-by-side benchmark of two builds (issue 48): a baseline and this tree, their runs
# interleaved (A, B, A, B, ...) so that both see the same machine load. Not a test.
#
#   benches/compare.sh                       # BASE_BIN=/work/tgt/base/release/day2night
#   BASE_BIN=/path/old NEW_BIN=/path/new benches/compare.sh
#   BASE_SRC=/path/to/old/checkout benches/compare.sh   # builds the baseline there
#   RUNS=9 DATASET_RUNS=5 benches/compare.sh
#   DATASET=0 benches/compare.sh             # skip the dataset rows
#   BIG=1 benches/compare.sh                 # also the 109 MP default synth (peak RSS)
#   WORK=DIR benches/compare.sh              # scratch directory (default: mktemp -d)
#   NO_BUILD=1 benches/compare.sh            # build nothing, take the binaries as they are
#   FRESH=1 BASE_FRESH=... NEW_FRESH=...     # also fresh training items (benches/fresh.rs
#                                            # built in each tree: cargo bench --bench fresh
#                                            # --no-run prints its path), FRESH_RUNS rounds
#
# Binaries: NEW_BIN defaults to this tree's release build (built here, CARGO_TARGET_DIR or
# target/); BASE_BIN to $BASE_SRC's release build when BASE_SRC is set (built with
# CARGO_TARGET_DIR=$BASE_TARGET, default /work/tgt/base), else /work/tgt/base/release.
# Input: the deterministic 12 MP 10-bit RGGB DNG of benches/run.sh (make_bench_input);
# with BIG=1 also that image tiled 3 x 3 (109.7 M sites, make_tiled_input), as in
# docs/benchmarks.md ("Peak memory at 109 MP").
# Rows (median of RUNS interleaved runs, GNU time):
#   synth --target both --jobs 2 --seed 1        CPU s (user+sys), wall s, peak RSS MB
#   dataset (20 copies) --jobs 2 --target both   the same, plus images/s (DATASET_RUNS)
#   synth 109 MP (defaults) with BIG=1           the same, plus bytes of peak RSS per site
# Needs GNU time (/usr/bin/time; Debian package `time`).
set -euo pipefail

RUNS=${RUNS:-7}
DATASET=${DATASET:-1}
DATASET_RUNS=${DATASET_RUNS:-3}
BIG=${BIG:-0}
BIG_RUNS=${BIG_RUNS:-3}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}

if [ ! -x /usr/bin/time ]; then
    echo "benches/compare.sh: GNU time missing: apt-get install -y time" >&2
    exit 1
fi

cd "$ROOT"
# NO_BUILD=1: take the binaries and examples already built
[ "${NO_BUILD:-0}" = 1 ] ||
    cargo build --release --quiet --bin day2night --example make_bench_input --example make_tiled_input
NEW_BIN=${NEW_BIN:-$CARGO_TARGET_DIR/release/day2night}
GEN=$CARGO_TARGET_DIR/release/examples/make_bench_input
TILE=$CARGO_TARGET_DIR/release/examples/make_tiled_input
if [ -z "${BASE_BIN:-}" ]; then
    if [ -n "${BASE_SRC:-}" ]; then
        BASE_TARGET=${BASE_TARGET:-/work/tgt/base}
        [ "${NO_BUILD:-0}" = 1 ] ||
            (cd "$BASE_SRC" && CARGO_TARGET_DIR=$BASE_TARGET cargo build --release --quiet --bin day2night)
        BASE_BIN=$BASE_TARGET/release/day2night
    else
        BASE_BIN=/work/tgt/base/release/day2night
    fi
fi
for b in "$BASE_BIN" "$NEW_BIN"; do
    if [ ! -x "$b" ]; then
        echo "benches/compare.sh: no binary at $b (set BASE_BIN / NEW_BIN or BASE_SRC)" >&2
        exit 1
    fi
done

WORK=${WORK:-$(mktemp -d -t d2n-compare.XXXXXX)}
mkdir -p "$WORK"
IN=$WORK/day.dng
[ -f "$IN" ] || "$GEN" "$IN"

# one NAME CMD...: one run (after a clean of $WORK/out), "wall_s rss_kb user_s sys_s"
# appended to $WORK/NAME.times
one() {
    local name=$1
    shift
    rm -rf "$WORK/out"
    /usr/bin/time -f "%e %M %U %S" -o "$WORK/$name.one" "$@" >/dev/null
    cat "$WORK/$name.one" >>"$WORK/$name.times"
}

# pair NAME RUNS ARGS...: RUNS rounds of (baseline, new) with the same arguments,
# alternating which goes first
pair() {
    local name=$1 runs=$2
    shift 2
    : >"$WORK/$name.base.times"
    : >"$WORK/$name.new.times"
    for i in $(seq "$runs"); do
        if [ $((i % 2)) = 1 ]; then
            one "$name.base" "$BASE_BIN" "$@"
            one "$name.new" "$NEW_BIN" "$@"
        else
            one "$name.new" "$NEW_BIN" "$@"
            one "$name.base" "$BASE_BIN" "$@"
        fi
    done
}

load0=$(cut -d' ' -f1-3 /proc/loadavg)
pair synth "$RUNS" synth "$IN" -o "$WORK/out" --target both --jobs 2 --seed 1 -q
if [ "$DATASET" = 1 ]; then
    mkdir -p "$WORK/days"
    for i in $(seq -w 1 20); do
        [ -e "$WORK/days/day$i.dng" ] || cp "$IN" "$WORK/days/day$i.dng"
    done
    pair dataset "$DATASET_RUNS" dataset "$WORK/days" -o "$WORK/out" --jobs 2 --quiet \
        --target both --seed 1
fi
if [ "$BIG" = 1 ]; then
    BIG_IN=$WORK/day109.dng
    [ -f "$BIG_IN" ] || "$TILE" "$IN" "$BIG_IN"
    pair big "$BIG_RUNS" synth "$BIG_IN" -o "$WORK/out" -q
fi
if [ "${FRESH:-0}" = 1 ]; then
    # one bench run prints "plan + item ... = N patches of 64x64 per second" (one thread)
    : >"$WORK/fresh.base.rates"
    : >"$WORK/fresh.new.rates"
    for i in $(seq "${FRESH_RUNS:-5}"); do
        for b in base new; do
            bin=$BASE_FRESH
            [ "$b" = new ] && bin=$NEW_FRESH
            D2N_FRESH_DNG=$IN D2N_FRESH_ITEMS=${FRESH_ITEMS:-100} "$bin" |
                sed -n 's/.*= \([0-9]*\) patches.*/\1/p' >>"$WORK/fresh.$b.rates"
        done
    done
fi
load1=$(cut -d' ' -f1-3 /proc/loadavg)

# med FILE COLUMN-EXPR: median of an awk expression over the runs
med() {
    awk "{print $2}" "$1" | sort -g | awk '{v[NR]=$1} END {
        printf "%.3f", (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2 }'
}

echo
echo "machine: $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p' | head -1)," \
    "$(free -g | awk '/^Mem:/{print $2}') GiB; load (1/5/15 min) before: $load0, after: $load1"
echo "baseline: $BASE_BIN"
echo "new:      $NEW_BIN"
printf "%-40s %-5s %5s %8s %8s %10s %10s\n" configuration build runs cpu_s wall_s peakRSS_MB extra
row() {
    local label=$1 name=$2 build=$3 extra=${4:-}
    local f=$WORK/$name.$build.times
    local cpu wall rss n
    cpu=$(med "$f" '$3 + $4')
    wall=$(med "$f" '$1')
    rss=$(med "$f" '$2 / 1024')
    n=$(wc -l <"$f")
    local x=""
    case $extra in
    ips) x="$(echo "20 / $wall" | bc -l | xargs printf %.2f) img/s" ;;
    bpp) x="$(echo "$(med "$f" '$2') * 1024 / 109734912" | bc -l | xargs printf %.2f) B/px" ;;
    esac
    printf "%-40s %-5s %5s %8s %8s %10.1f %10s\n" "$label" "$build" "$n" "$cpu" "$wall" "$rss" "$x"
}
ratio() {
    local name=$1 expr=$2 what=$3
    local b n
    b=$(med "$WORK/$name.base.times" "$expr")
    n=$(med "$WORK/$name.new.times" "$expr")
    printf "  %s new/base: %.3f\n" "$what" "$(echo "$n / $b" | bc -l)"
}
row "synth 12 MP --target both --jobs 2" synth base
row "" synth new
ratio synth '$3 + $4' "CPU"
ratio synth '$1' "wall"
if [ "$DATASET" = 1 ]; then
    row "dataset 20 x 12 MP --jobs 2 --target both" dataset base ips
    row "" dataset new ips
    ratio dataset '$1' "wall (images/s is its inverse)"
fi
if [ "$BIG" = 1 ]; then
    row "synth 109 MP (defaults)" big base bpp
    row "" big new bpp
    ratio big '$2' "peak RSS"
fi
if [ "${FRESH:-0}" = 1 ]; then
    fb=$(med "$WORK/fresh.base.rates" '$1')
    fn=$(med "$WORK/fresh.new.rates" '$1')
    printf "%-40s base %s, new %s patches/s (one core); new/base %.3f\n" \
        "fresh 64x64 patches (benches/fresh.rs)" "$fb" "$fn" "$(echo "$fn / $fb" | bc -l)"
fi
echo "medians of interleaved runs; cpu_s = user + system; raw times (wall_s rss_kb user_s" \
    "sys_s per run): $WORK/*.times"
