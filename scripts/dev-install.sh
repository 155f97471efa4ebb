#!/usr/bin/env bash
# day2night from a checkout, the documented way (README.md, "Install"): nothing is published
# on a package index yet, so the wheel is built here and installed into a virtualenv.
#   scripts/dev-install.sh [VENV] [--no-train]        (default VENV: .venv)
# 1. VENV is made if missing (python3 -m venv), with the wheel's build tools
#    (scripts/wheel-requirements.txt: ziglang, cargo-zigbuild, ...) and maturin;
# 2. the release `day2night` binary is built with `cargo build --release` (the one README.md's
#    main command `cargo run --release -- synth ...` builds: nothing to compile again after
#    it, and it after this), then scripts/wheel.sh builds the wheel of the Python extension
#    with that binary as its script (D2N_WHEEL_BIN; a wheel for this machine);
#    D2N_WHEEL=PATH installs that wheel instead (scripts/test.sh passes the one it built);
# 3. the wheel goes into VENV with the `train` extra (torch; --no-train: without), replacing
#    an earlier build of the same version;
# 4. checked: VENV/bin/day2night --version is the wheel's version and
#    `import day2night.train` works (without torch, unless --no-train).
# Then `. VENV/bin/activate` puts `day2night` on PATH and `python` has the package.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=.venv
train=1
for a in "$@"; do
  case "$a" in
    --no-train) train=0 ;;
    -*) echo "scripts/dev-install.sh: unknown option $a (usage: scripts/dev-install.sh [VENV] [--no-train])" >&2; exit 2 ;;
    *) venv="$a" ;;
  esac
done
fail() { echo "scripts/dev-install.sh: $*" >&2; exit 1; }
wheel="${D2N_WHEEL:-}"
[ -z "$wheel" ] || [ -f "$wheel" ] || fail "no wheel at $wheel (D2N_WHEEL)"
mkdir -p "$(dirname "$venv")"
venv="$(cd "$(dirname "$venv")" && pwd)/$(basename "$venv")"
py="$venv/bin/python"
if [ ! -x "$py" ]; then
  echo "scripts/dev-install.sh: making the virtualenv $venv" >&2
  python3 -m venv "$venv" || fail "python3 -m venv $venv failed (Python 3.9+ with venv is needed)"
fi
if [ -z "$wheel" ]; then
  for t in maturin cargo-zigbuild; do
    if [ ! -x "$venv/bin/$t" ]; then
      echo "scripts/dev-install.sh: installing the wheel's build tools into $venv" >&2
      "$py" -m pip install --quiet --disable-pip-version-check --only-binary=:all: \
        "maturin>=1.9,<2" -r scripts/wheel-requirements.txt
      break
    fi
  done
  echo "scripts/dev-install.sh: building the day2night binary (cargo build --release)" >&2
  cargo build --quiet --release --locked --bin day2night || fail "cargo build --release failed"
  bin="${CARGO_TARGET_DIR:-$PWD/target}/release/day2night"
  wheel=$(D2N_WHEEL_BIN="$bin" D2N_WHEEL_PYTHON="$py" scripts/wheel.sh | tail -1)
fi
[ -f "$wheel" ] || fail "scripts/wheel.sh gave no wheel ($wheel)"
version=$(sed -n 's/^version = "\(.*\)"/\1/p' python/pyproject.toml | head -1)
# the wheel itself, replacing an installed build of the same version; then its
# dependencies (numpy; torch with the train extra) where they are missing
"$py" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps "$wheel"
if [ "$train" = 1 ]; then
  "$py" -m pip install --quiet --disable-pip-version-check "$wheel[train]"
else
  "$py" -m pip install --quiet --disable-pip-version-check "$wheel"
fi
got=$("$venv/bin/day2night" --version) || fail "$venv/bin/day2night does not run"
[ "$got" = "day2night $version" ] || fail "$venv/bin/day2night --version says '$got', expected 'day2night $version'"
if [ "$train" = 1 ]; then
  "$py" -c "import day2night.train, torch" || fail "import day2night.train with torch failed in $venv"
else
  "$py" -c "import day2night, day2night.train" || fail "import day2night failed in $venv"
fi
echo "scripts/dev-install.sh: $got and the Python package$([ "$train" = 1 ] && echo " with its train extra") in $venv" >&2
echo "scripts/dev-install.sh: '. $venv/bin/activate' puts day2night on PATH" >&2
echo "$venv"
