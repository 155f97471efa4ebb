#!/usr/bin/env bash
# The whole test suite with its set-up, on a fresh machine:
#   1. a local Python virtualenv (.venv) with the independent validators
#      (rawpy/LibRaw, dngpy/Adobe DNG SDK, tifffile, OpenEXR, OpenImageIO, numpy, ...),
#      maturin and pytest;
#   2. cargo test (unit, integration, doc tests); tests find the validators through
#      D2N_PYTHON and fail (instead of skipping) when D2N_REQUIRE_VALIDATORS=1;
#   3. the wheel users install (scripts/wheel.sh: the Python extension and the release
#      binary, manylinux2014), built once and installed into the same venv (with ray[data]
#      from python/tests/requirements-ray.txt where it has wheels, and torch from
#      python/tests/requirements-train.txt); scripts/wheel-check.sh runs that wheel in a
#      fresh venv without cargo/rustc against the CLI built in 2 (installed into the venv by
#      scripts/dev-install.sh, the documented way from a checkout); then the pytest suite
#      (python/tests), which compares the package with the CLI built in 2.
# Nothing passes without testing (tests/README.md): a missing validator, exiftool, chromium,
# iinfo or GNU time fails the run; D2N_REQUIRE_TOOLS=0 (local runs) instead declares the
# missing tools absent (D2N_ALLOW_MISSING), and the tests needing them are reported as
# ignored. Tests that need the real-camera files of ../shared/data (or $D2N_SHARED_DATA) are
# reported as ignored when those were absent at build time; D2N_REQUIRE_SHARED_DATA=1 (set
# by .ci/run when ../shared/data exists) makes them fail instead.
# --slow: also the slow tests (#[ignore = "slow: ..."], names slow_*), in a release build, and
# the docs' slow blocks (D2N_SLOW=1: python/tests/test_docs_run.py, "docs-run: slow").
# Extra arguments go to cargo test, e.g. scripts/test.sh --test it dng_roundtrip:: (then the
# Python suite is skipped; D2N_PYTHON_TESTS=1 runs it anyway, D2N_PYTHON_TESTS=0 never).
set -euo pipefail
cd "$(dirname "$0")/.."

# --- --slow (issue 30): taken out of the cargo arguments ---------------------------------
slow=0
cargo_args=()
for a in "$@"; do
  if [ "$a" = --slow ]; then slow=1; else cargo_args+=("$a"); fi
done
set -- ${cargo_args[@]+"${cargo_args[@]}"}

# --- required tools (issue 30): missing ones fail, or are declared absent ----------------
export D2N_REQUIRE_TOOLS="${D2N_REQUIRE_TOOLS:-1}"
missing_tools=()
missing_names=()
command -v exiftool >/dev/null 2>&1 || { missing_tools+=("exiftool (Debian libimage-exiftool-perl)"); missing_names+=(exiftool); }
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 \
  || command -v google-chrome >/dev/null 2>&1 || { missing_tools+=("chromium (Debian chromium)"); missing_names+=(chromium); }
[ -x /usr/bin/time ] || { missing_tools+=("GNU time at /usr/bin/time (Debian time)"); missing_names+=(time); }
[ -x "${D2N_IINFO:-/usr/bin/iinfo}" ] || missing_tools+=("iinfo (Debian openimageio-tools)")
if [ "${#missing_tools[@]}" -gt 0 ]; then
  if [ "$D2N_REQUIRE_TOOLS" = 1 ]; then
    printf 'scripts/test.sh: missing: %s\n' "${missing_tools[@]}" >&2
    echo "scripts/test.sh: install them (.ci/run does, as root on Debian), or run with D2N_REQUIRE_TOOLS=0 to report their tests as ignored/skipped" >&2
    exit 1
  fi
  printf 'scripts/test.sh: D2N_REQUIRE_TOOLS=0: not testing with %s\n' "${missing_tools[@]}" >&2
  if [ "${#missing_names[@]}" -gt 0 ]; then
    list=$(IFS=,; echo "${missing_names[*]}")
    export D2N_ALLOW_MISSING="${D2N_ALLOW_MISSING:+$D2N_ALLOW_MISSING,}$list"
  fi
fi
# --- end required tools -------------------------------------------------------------------
VENV="${D2N_VENV:-$PWD/.venv}"
REQ=tests/validators/requirements.txt
stamp="$VENV/.requirements.sha"
want=$(sha256sum "$REQ" | cut -d' ' -f1)
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "scripts/test.sh: setting up validators in $VENV" >&2
  python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$REQ"
  echo "$want" > "$stamp"
fi
export D2N_PYTHON="$VENV/bin/python"
export D2N_REQUIRE_VALIDATORS="${D2N_REQUIRE_VALIDATORS:-1}"

# ---- packaging tools and docs (issue 29) ------------------------------------------------
# zig, cargo-zigbuild, auditwheel and actionlint (scripts/wheel-requirements.txt), stamped
# like the validators; then the crate's docs with rustdoc's warnings denied (about 1 min).
wheel_req=scripts/wheel-requirements.txt
wheel_stamp="$VENV/.wheel-requirements.sha"
wheel_want=$(sha256sum "$wheel_req" | cut -d' ' -f1)
if [ "$(cat "$wheel_stamp" 2>/dev/null)" != "$wheel_want" ]; then
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: -r "$wheel_req"
  echo "$wheel_want" > "$wheel_stamp"
fi
if [ "$#" -eq 0 ]; then
  echo "scripts/test.sh: cargo doc --no-deps with rustdoc's warnings denied" >&2
  RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps --locked
fi
# ---- end of packaging tools and docs ----------------------------------------------------

cargo test "$@"

# --- --slow (issue 30): the ignored slow tests, release build ------------------------------
if [ "$slow" = 1 ]; then
  has_sep=0
  for a in "$@"; do [ "$a" = -- ] && has_sep=1; done
  if [ "$has_sep" = 1 ]; then
    cargo test --release "$@" --ignored slow_
  else
    cargo test --release "$@" -- --ignored slow_
  fi
fi
# --- end --slow ---------------------------------------------------------------------------

py_tests="${D2N_PYTHON_TESTS:-}"
if [ -z "$py_tests" ]; then
  if [ "$#" -eq 0 ]; then py_tests=1; else py_tests=0; fi
fi
if [ "$py_tests" = 1 ]; then
  # Ray Data for python/tests/test_ray.py, where wheels exist for this platform and Python
  # (about 50 s on the 2-core machine, once: stamped like the validators). Installed, the
  # test must run (D2N_REQUIRE_RAY=1); not installable, it skips with the reason, unless
  # D2N_REQUIRE_RAY=1 was set by the caller (CI), which makes that an error.
  ray_req=python/tests/requirements-ray.txt
  ray_stamp="$VENV/.ray-requirements.sha"
  ray_want=$(sha256sum "$ray_req" | cut -d' ' -f1)
  if [ "$(cat "$ray_stamp" 2>/dev/null)" = "$ray_want" ]; then
    export D2N_REQUIRE_RAY=1
  elif "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: -r "$ray_req"; then
    echo "$ray_want" > "$ray_stamp"
    export D2N_REQUIRE_RAY=1
  elif [ "${D2N_REQUIRE_RAY:-}" = 1 ]; then
    echo "scripts/test.sh: D2N_REQUIRE_RAY=1 but $ray_req could not be installed" >&2
    exit 1
  else
    export D2N_RAY_SKIP_REASON="ray[data] could not be installed from $ray_req (no wheel for this platform or Python, or no network): test_ray.py skipped"
    echo "scripts/test.sh: $D2N_RAY_SKIP_REASON" >&2
  fi
  # PyTorch for the night ISP trainer's tests (python/tests/test_train_*.py; the package's
  # [train] extra): torch from PyPI brings its CUDA libraries (see README.md for what that
  # costs), installed once and stamped like the validators. Installed, the tests must run
  # (D2N_REQUIRE_TORCH=1); not installable, they skip with the reason, unless the caller set
  # D2N_REQUIRE_TORCH=1 (then that is an error).
  torch_req=python/tests/requirements-train.txt
  torch_stamp="$VENV/.train-requirements.sha"
  torch_want=$(sha256sum "$torch_req" | cut -d' ' -f1)
  # An install that pip reports done is stamped only once `import torch` works: one cut
  # short (a full disk, a lost connection) can leave torch's files half there, and pip
  # then calls the requirement satisfied. Not stamped, such a venv is tried again next time
  # and its tests skip with the import's error (D2N_REQUIRE_TORCH=1: fail) meanwhile.
  torch_err=""
  torch_check() {
    local out
    out=$("$VENV/bin/python" -c "import torch, tensorboard" 2>&1) || { echo "$out" | tail -1; return 1; }
  }
  if [ "$(cat "$torch_stamp" 2>/dev/null)" = "$torch_want" ]; then
    export D2N_REQUIRE_TORCH=1
  elif "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --only-binary=:all: -r "$torch_req" \
      && torch_err=$(torch_check); then
    echo "$torch_want" > "$torch_stamp"
    export D2N_REQUIRE_TORCH=1
  elif [ "${D2N_REQUIRE_TORCH:-}" = 1 ]; then
    echo "scripts/test.sh: D2N_REQUIRE_TORCH=1 but $torch_req could not be installed${torch_err:+ ($torch_err)}" >&2
    exit 1
  else
    export D2N_TORCH_SKIP_REASON="torch could not be installed from $torch_req (no wheel for this platform or Python, no network, or an install cut short${torch_err:+: $torch_err}): the tests that need it skipped"
    echo "scripts/test.sh: $D2N_TORCH_SKIP_REASON" >&2
  fi
  export D2N_BIN="${CARGO_TARGET_DIR:-$PWD/target}/debug/day2night"
  # ---- the wheel (issue 29) -------------------------------------------------------------
  # Built once (scripts/wheel.sh), installed here in place of `pip install ./python`, and
  # checked in a fresh venv without cargo/rustc against the cargo-built CLI.
  echo "scripts/test.sh: building the wheel (scripts/wheel.sh) and installing it into $VENV" >&2
  wheel=$(D2N_WHEEL_PYTHON="$VENV/bin/python" scripts/wheel.sh | tail -1)
  # installed the documented way (scripts/dev-install.sh, README.md "Install"), with the
  # train extra where torch is installed (its dependencies are then already there)
  train_flag=--no-train
  [ "${D2N_REQUIRE_TORCH:-}" = 1 ] && train_flag=
  D2N_WHEEL="$wheel" scripts/dev-install.sh "$VENV" $train_flag >/dev/null
  export D2N_DEV_VENV="$VENV" D2N_DEV_TRAIN="$([ -z "$train_flag" ] && echo 1 || echo 0)"
  D2N_WHEEL_PYTHON="$VENV/bin/python" scripts/wheel-check.sh "$wheel" "$D2N_BIN"
  if [ "${D2N_PACKAGE_CHECK:-0}" = 1 ]; then
    D2N_WHEEL_PYTHON="$VENV/bin/python" scripts/package-check.sh
  fi
  # ---- end of the wheel -----------------------------------------------------------------
  # --slow: also the docs' slow blocks (docs-run: slow, e.g. the experiment's mini preset)
  if [ "$slow" = 1 ]; then export D2N_SLOW=1; fi
  "$VENV/bin/python" -m pytest -q python/tests
fi
