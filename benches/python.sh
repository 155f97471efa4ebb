#!/usr/bin/env bash
# Python package benchmark (issue 12): builds the package into the test virtualenv, makes
# the 12 MP benchmark input (examples/make_bench_input.rs) and runs benches/python_pairs.py.
#   benches/python.sh [ARGS for python_pairs.py, e.g. --runs 7]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
VENV="${D2N_VENV:-$ROOT/.venv}"
[ -x "$VENV/bin/python" ] || { echo "benches/python.sh: run scripts/test.sh once first (it makes $VENV)" >&2; exit 1; }
PATH="$VENV/bin:$PATH" "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-build-isolation --no-deps ./python
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
cargo build --release --quiet --example make_bench_input
WORK=${WORK:-$(mktemp -d -t d2n-pybench.XXXXXX)}
mkdir -p "$WORK/in"
[ -f "$WORK/in/day.dng" ] || "$CARGO_TARGET_DIR/release/examples/make_bench_input" "$WORK/in/day.dng"
"$VENV/bin/python" benches/python_pairs.py "$WORK/in/day.dng" "$@"
