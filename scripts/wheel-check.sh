#!/usr/bin/env bash
# What a user gets from the wheel, on a machine without Rust (docs/release.md, "The wheel"):
#   scripts/wheel-check.sh WHEEL REFERENCE_BIN
# 1. auditwheel (from the venv of $D2N_WHEEL_PYTHON) reports manylinux2014 or older, and the
#    binary in the wheel asks for no glibc symbol newer than 2.17 (readelf);
# 2. the wheel is installed into a fresh venv (with numpy from the index) and run there
#    with a PATH that holds the venv, /usr/bin and /bin only (no cargo, no rustc):
#    `day2night --version`; `day2night synth fixtures/day.dng -o OUT`, whose files are
#    byte-identical to REFERENCE_BIN's (the cargo-built binary); and one
#    `day2night.synthesize` call equal to the CLI's output.
# Called by scripts/test.sh on the wheel it built; the venv is made under a temp folder.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
wheel="$(realpath "${1:?usage: scripts/wheel-check.sh WHEEL REFERENCE_BIN}")"
ref="$(realpath "${2:?usage: scripts/wheel-check.sh WHEEL REFERENCE_BIN}")"
py="${D2N_WHEEL_PYTHON:-$(command -v python3)}"
fail() { echo "scripts/wheel-check.sh: $*" >&2; exit 1; }
t0=$(date +%s)

# 1. Platform tag and glibc symbol versions.
tag=$("$(dirname "$py")/auditwheel" show "$wheel" 2>&1) || fail "auditwheel show failed: $tag"
policy=$(printf '%s\n' "$tag" | grep -o 'manylinux_2_[0-9]*_[a-z0-9_]*' | head -1)
minor=$(printf '%s' "$policy" | sed -n 's/manylinux_2_\([0-9]*\)_.*/\1/p')
[ -n "$minor" ] && [ "$minor" -le 17 ] || fail "auditwheel: $wheel is not manylinux2014 or older: $tag"
echo "wheel-check: auditwheel: $policy (manylinux2014 or older)"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$py" -m zipfile -e "$wheel" "$work/unzipped"
bin=$(ls "$work"/unzipped/day2night-*.data/scripts/day2night)
newest=$(readelf -W --version-info "$bin" | grep -o 'GLIBC_[0-9.]*' | sort -t. -k1,1 -k2,2n -k3,3n -V | tail -1)
[ "$(printf '%s\nGLIBC_2.17\n' "$newest" | sort -V | tail -1)" = GLIBC_2.17 ] \
  || fail "the binary in the wheel needs $newest (more than GLIBC_2.17)"
echo "wheel-check: binary's newest glibc symbol version: $newest"

# 2. A fresh venv, without cargo or rustc on PATH.
"$py" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$wheel"
clean_path="$work/venv/bin:/usr/bin:/bin"
for tool in cargo rustc; do
  if PATH="$clean_path" command -v "$tool" >/dev/null 2>&1; then
    fail "$tool is on the clean PATH ($clean_path)"
  fi
done
run() { env -i HOME="$work" PATH="$clean_path" "$@"; }
[ "$(run sh -c "command -v day2night")" = "$work/venv/bin/day2night" ] || fail "day2night is not the venv's command"
want="day2night $(sed -n 's/^version = "\(.*\)"/\1/p' python/pyproject.toml | head -1)"
got=$(run day2night --version)
[ "$got" = "$want" ] || fail "day2night --version says '$got', expected '$want'"
echo "wheel-check: $got"

run day2night synth "$root/fixtures/day.dng" -o "$work/wheel_out" --seed 7 --iso 800,3200 >/dev/null 2>"$work/wheel.err" \
  || fail "day2night synth failed: $(cat "$work/wheel.err")"
"$ref" synth "$root/fixtures/day.dng" -o "$work/ref_out" --seed 7 --iso 800,3200 >/dev/null 2>&1
diff -r "$work/wheel_out" "$work/ref_out" >/dev/null || fail "the wheel's synth outputs differ from $ref's"
echo "wheel-check: synth outputs byte-identical to $ref ($(ls "$work/wheel_out" | wc -l) files)"

run python -W ignore::UserWarning - "$root/fixtures/day.dng" "$work/wheel_out" <<'PY' || fail "the Python API differs from the CLI"
import sys
import numpy as np
import day2night
day, out = sys.argv[1], sys.argv[2]
raw = day2night.read_dng(day)
res = day2night.synthesize(raw, seed=7, isos=(800, 3200))
assert np.array_equal(res["clean"], day2night.read_dng(f"{out}/day_clean.dng").data), "clean"
for iso in (800, 3200):
    noisy = day2night.read_dng(f"{out}/day_iso{iso}.dng").data
    assert np.array_equal(res["noisy"][iso], noisy), iso
print(f"wheel-check: import day2night {day2night.version()}: synthesize equals the CLI's outputs")
PY
echo "wheel-check: passed in $(( $(date +%s) - t0 )) s"
