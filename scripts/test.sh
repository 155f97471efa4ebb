#!/usr/bin/env bash
# The whole test suite with its set-up, on a fresh machine:
#   1. a local Python virtualenv (.venv) with the independent validators
#      (rawpy/LibRaw, dngpy/Adobe DNG SDK, tifffile, OpenEXR, OpenImageIO, numpy, ...),
#   2. cargo test (unit, integration, doc tests); tests find the validators through
#      D2N_PYTHON and fail (instead of skipping) when D2N_REQUIRE_VALIDATORS=1.
# exiftool is used when installed (.ci/run installs it). Slow suites: D2N_SLOW=1.
# Extra arguments go to cargo test, e.g. scripts/test.sh --test dng_roundtrip.
set -euo pipefail
cd "$(dirname "$0")/.."
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
cargo test "$@"
