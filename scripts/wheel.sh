#!/usr/bin/env bash
# Build the one wheel of day2night (docs/release.md, "The wheel"): the Python extension
# (day2night._native, the library without the `cli` feature) and the `day2night` release
# binary in the wheel's scripts (day2night-<v>.data/scripts/day2night, which pip installs
# on the environment's PATH), both linked through zig for manylinux2014 (glibc 2.17).
#   scripts/wheel.sh [OUT_DIR]      (default $CARGO_TARGET_DIR/wheels or target/wheels)
# Prints the wheel's path as its last line on stdout. Needs cargo, and maturin, ziglang and
# cargo-zigbuild (PyPI) beside the python of $D2N_WHEEL_PYTHON (default: the one on PATH).
# D2N_WHEEL_BIN=PATH puts that binary in the wheel instead of building the glibc 2.17 one
# (scripts/dev-install.sh passes `cargo build --release`'s, the binary README.md's main
# command builds, so a checkout compiles it once): such a wheel is for this machine only.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
py="${D2N_WHEEL_PYTHON:-$(command -v python3)}"
tools="$(dirname "$py")"
for t in maturin cargo-zigbuild; do
  if [ ! -x "$tools/$t" ]; then
    echo "scripts/wheel.sh: $t not found beside $py (pip install maturin ziglang cargo-zigbuild)" >&2
    exit 1
  fi
done
"$py" -c "import ziglang" 2>/dev/null || {
  echo "scripts/wheel.sh: the ziglang package is not installed for $py (pip install ziglang)" >&2
  exit 1
}
target_dir="${CARGO_TARGET_DIR:-$root/target}"
out="${1:-$target_dir/wheels}"
host=$(rustc -vV | sed -n 's/^host: //p')
glibc=2.17
export PATH="$tools:$PATH"

# 1. The command-line binary, for glibc 2.17 (cargo-zigbuild's "<triple>.<glibc>" target),
# unless D2N_WHEEL_BIN names one already built.
bin="${D2N_WHEEL_BIN:-}"
if [ -n "$bin" ]; then
  [ -x "$bin" ] || { echo "scripts/wheel.sh: D2N_WHEEL_BIN=$bin is not an executable file" >&2; exit 1; }
  echo "scripts/wheel.sh: the day2night binary $bin (D2N_WHEEL_BIN: this machine's, not glibc $glibc)" >&2
else
  echo "scripts/wheel.sh: building the day2night binary for $host, glibc $glibc" >&2
  # Stripped, like the wheel's extension (pyproject.toml `strip = true`): the release profile
  # keeps line tables for backtraces, which a user's installed command does not need.
  CARGO_PROFILE_RELEASE_STRIP=symbols \
    cargo-zigbuild zigbuild --quiet --release --locked --bin day2night --target "$host.$glibc" >&2
  bin="$target_dir/$host/release/day2night"
fi

# 2. The wheel of the extension (abi3), tagged manylinux2014.
echo "scripts/wheel.sh: building the wheel (maturin --zig, manylinux2014)" >&2
mkdir -p "$out"
maturin build --quiet --release --locked --zig --compatibility manylinux2014 \
  --target "$host" -m python/Cargo.toml -o "$out" >&2
version=$(sed -n 's/^version = "\(.*\)"/\1/p' python/pyproject.toml | head -1)
wheel=$(ls -t "$out"/day2night-"$version"-*manylinux*.whl | head -1)

# 3. The binary into the wheel's scripts (scripts/wheel_add_script.py: added after the
# build, so that maturin needs no data folder, which the sdist and `pip install ./python`
# would then need too).
"$py" scripts/wheel_add_script.py "$wheel" "$bin" >&2
if ! "$py" -c 'import sys, zipfile; sys.exit(sys.argv[2] not in zipfile.ZipFile(sys.argv[1]).namelist())' \
  "$wheel" "day2night-$version.data/scripts/day2night"; then
  echo "scripts/wheel.sh: $wheel has no day2night-$version.data/scripts/day2night" >&2
  exit 1
fi
echo "$wheel"
