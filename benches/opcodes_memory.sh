#!/usr/bin/env bash
# The opcode-path measurements of issue 26 (docs/benchmarks.md, "DNG opcodes: work and
# memory"): wall time and peak RSS (GNU time, median of RUNS) of `render` and `synth` on
# the inputs of benches/make_opcode_inputs.py:
#   96 MP plain, one identity warp, one real warp (WarpRectilinear; WarpRectilinear2;
#   WarpFisheye; WarpRectilinear with Orientation 6) (render to EXR, synth default)
#   4096 identity warps on 2048 x 1536 (render), 4096 real warps (refused), 4096
#   FixBadPixelsConstant on 512 x 384 (render)
#
#   benches/opcodes_memory.sh                       # this checkout's release build
#   D2N_BIN=/path/to/old/day2night benches/opcodes_memory.sh   # another build
#   RUNS=5 WORK=/tmp/d2n-op benches/opcodes_memory.sh
#   SKIP='4096' benches/opcodes_memory.sh           # skip the rows whose name matches
# Needs GNU time (Debian package `time`) and the validators' Python (tifffile, imagecodecs,
# the day2night wheel) in D2N_PYTHON (default: python3) to make the inputs once into $WORK/in.
set -euo pipefail
RUNS=${RUNS:-3}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
PY=${D2N_PYTHON:-python3}
WORK=${WORK:-/tmp/d2n-opcodes}
mkdir -p "$WORK"
if [ -z "${D2N_BIN:-}" ]; then
    (cd "$ROOT" && cargo build --release --quiet --bin day2night)
fi
BIN=${D2N_BIN:-$CARGO_TARGET_DIR/release/day2night}
IN=$WORK/in
[ -f "$IN/fix4096.dng" ] && [ -f "$IN/realwarp96o6.dng" ] || "$PY" "$ROOT/benches/make_opcode_inputs.py" "$IN"

# one NAME CMD...: RUNS runs, prints "NAME median-wall median-rss-KiB exit-code"
one() {
    local name=$1
    shift
    if [[ -n "${SKIP:-}" && "$name" =~ $SKIP ]]; then
        echo "$name skipped"
        return
    fi
    local t=$WORK/$name.times
    : >"$t"
    for _ in $(seq "$RUNS"); do
        rm -rf "$WORK/out"
        mkdir -p "$WORK/out"
        local code=0
        /usr/bin/time -f "%e %M" -o "$WORK/one" "$@" >/dev/null 2>"$WORK/$name.err" || code=$?
        echo "$(tail -1 "$WORK/one") $code" >>"$t"
    done
    local wall rss
    wall=$(cut -d' ' -f1 "$t" | sort -n | sed -n "$(((RUNS + 1) / 2))p")
    rss=$(cut -d' ' -f2 "$t" | sort -n | sed -n "$(((RUNS + 1) / 2))p")
    echo "$name $wall $rss $(cut -d' ' -f3 "$t" | sort -u | tr '\n' ' ')"
}
uptime
for f in plain96 warp96 realwarp96 warp2_96 fisheye96 realwarp96o6; do
    one "render-$f" "$BIN" render "$IN/$f.dng" -o "$WORK/out/r.exr"
    one "synth-$f" "$BIN" synth "$IN/$f.dng" -o "$WORK/out"
done
one render-warps4096 "$BIN" render "$IN/warps4096.dng" -o "$WORK/out/r.exr"
one render-realwarps4096 "$BIN" render "$IN/realwarps4096.dng" -o "$WORK/out/r.exr"
one render-fix4096 "$BIN" render "$IN/fix4096.dng" -o "$WORK/out/r.exr"
uptime
