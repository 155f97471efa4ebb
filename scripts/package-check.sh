#!/usr/bin/env bash
# The crate and the source distribution, as they would be published (docs/release.md):
#   1. `cargo package --list` (what the crate ships; no test data) and its size;
#   2. `cargo publish --dry-run` (packages and builds the crate on its own, from the
#      .crate file, as crates.io would; needs the crates.io index);
#   3. `maturin sdist` of python/, then `pip install` of that sdist into a fresh venv
#      (Rust present: it builds the extension) and `import day2night` there.
# Not part of the default test run (about 10 minutes of release builds on the 2-core
# machine); run it before a release, or with D2N_PACKAGE_CHECK=1 scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
py="${D2N_WHEEL_PYTHON:-$(command -v python3)}"
export PATH="$(dirname "$py"):$PATH"
fail() { echo "scripts/package-check.sh: $*" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# 1. The file list: sources and docs, never test data.
cargo package --list --allow-dirty --locked > "$work/list"
echo "package-check: $(wc -l < "$work/list") files in the crate"
# Code of tests/benches/examples ships (cargo drops targets without it, warning); their
# data does not: fixtures other than day.dng, the validators' scripts, regressions, fuzz.
bad=$(grep -E '^(fuzz|python|proptest-regressions|scripts|\.ci|\.github|fixtures|tests)/' "$work/list" \
  | grep -vx 'fixtures/day.dng' | grep -Ev '^tests/.*\.rs$' || true)
[ -z "$bad" ] || fail "the crate would ship test data or tooling (Cargo.toml's include list): $bad"
grep -qx 'src/lib.rs' "$work/list" || fail "src/lib.rs is not in the crate"

# 2. A dry-run publish: the packaged crate builds on its own.
cargo publish --dry-run --allow-dirty --locked --no-verify >/dev/null 2>"$work/publish.err" \
  || fail "cargo publish --dry-run (packaging): $(cat "$work/publish.err")"
if grep '^warning' "$work/publish.err" | grep -qv 'aborting upload due to dry run'; then
  fail "cargo package warns: $(grep '^warning' "$work/publish.err")"
fi
echo "package-check: $(grep -o 'Packaged .*' "$work/publish.err")"
cargo publish --dry-run --allow-dirty --locked >/dev/null 2>"$work/publish.err" \
  || fail "cargo publish --dry-run: $(tail -20 "$work/publish.err")"
echo "package-check: cargo publish --dry-run: the packaged crate builds"

# 3. The sdist builds and installs where Rust is present.
maturin sdist -m python/Cargo.toml -o "$work/sdist" >/dev/null 2>&1
sdist=$(ls "$work"/sdist/day2night-*.tar.gz)
echo "package-check: $(basename "$sdist"): $(stat -c %s "$sdist") bytes"
"$py" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet --disable-pip-version-check "$sdist" \
  || fail "pip install of the sdist failed"
"$work/venv/bin/python" -c "import day2night; print('package-check: sdist installs: import day2night', day2night.version())"
