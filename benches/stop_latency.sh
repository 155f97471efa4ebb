#!/usr/bin/env bash
# How long each command takes to exit after SIGTERM and SIGINT (docs/benchmarks.md,
# "Stopping on a signal"; docs/concurrency.md). tests/it/runs_interrupt.rs checks the exit
# codes and what is left on disk, never the time; this measures it.
#
#   held:    the command blocked reading an input that is a FIFO kept open (as the test
#            holds it): the signal path alone (synth and dataset wait out their grace);
#   working: `synth` of six copies of fixtures/day.dng (--jobs 2, --target both), signalled
#            after its first whole set, its stderr then a pipe nobody reads.
#
#   benches/stop_latency.sh            # this checkout's release build, 5 runs each
#   RUNS=9 D2N_BIN=/path/to/day2night benches/stop_latency.sh
set -euo pipefail
RUNS=${RUNS:-5}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
if [ -z "${D2N_BIN:-}" ]; then
    (cd "$ROOT" && cargo build --release --quiet --bin day2night)
    D2N_BIN=$ROOT/target/release/day2night
fi
B=$D2N_BIN
DAY=$ROOT/fixtures/day.dng
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
mkdir -p days
for k in 0 1 2 3 4 5; do cp "$DAY" "days/d$k.dng"; done
"$B" render "$DAY" -o a.png >/dev/null 2>&1

now_ms() { echo $(( $(date +%s%N) / 1000000 )); }
median() { sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# held NAME SIG ARGS... (the argument "GATE" is the FIFO)
held() {
    local name=$1 sig=$2
    shift 2
    local args=() t0 t1 rc
    for a in "$@"; do [ "$a" = GATE ] && args+=("$W/gate.dng") || args+=("$a"); done
    rm -rf gate.dng out && mkfifo gate.dng && mkdir out
    "$B" "${args[@]}" >/dev/null 2>&1 &
    local pid=$!
    exec 3>gate.dng # returns once the command opened its input
    t0=$(now_ms)
    kill "-$sig" "$pid"
    rc=0
    wait "$pid" || rc=$?
    t1=$(now_ms)
    exec 3>&-
    echo "$((t1 - t0)) $rc"
}

working() {
    local sig=$1 t0 t1 rc line
    rm -rf out err.fifo && mkfifo err.fifo
    "$B" synth days/*.dng -o out --jobs 2 --target both >/dev/null 2>err.fifo &
    local pid=$!
    while IFS= read -r line; do
        case $line in wrote*.json) break ;; esac
    done <err.fifo
    t0=$(now_ms)
    kill "-$sig" "$pid"
    rc=0
    wait "$pid" || rc=$?
    t1=$(now_ms)
    echo "$((t1 - t0)) $rc"
}

row() {
    local name=$1 sig=$2
    shift 2
    local times=() codes=() r
    for _ in $(seq "$RUNS"); do
        r=$("$@")
        times+=("${r% *}")
        codes+=("${r#* }")
    done
    printf '| %s | %s | %s | %s | %s |\n' "$name" "$sig" \
        "$(printf '%s\n' "${times[@]}" | sort -n | head -1)" \
        "$(printf '%s\n' "${times[@]}" | median)" \
        "$(printf '%s\n' "${codes[@]}" | sort -u | tr '\n' ' ')"
}

echo "| command | signal | min (ms) | median (ms) | exit |"
echo "|---|---|---|---|---|"
for sig in TERM INT; do
    row "render (held)" "$sig" held render "$sig" render GATE -o out/r.exr
    row "synth (held)" "$sig" held synth "$sig" synth GATE -o out
    row "dataset (held)" "$sig" held dataset "$sig" dataset days -o out/set --noise-model GATE
    row "eval (held)" "$sig" held eval "$sig" eval GATE a.png
    row "merge (held)" "$sig" held merge "$sig" merge GATE "$DAY" "$DAY" -o out/m.dng
    row "convert (held)" "$sig" held convert "$sig" convert GATE -o out/c.dng
    row "synth (working)" "$sig" working "$sig"
done
