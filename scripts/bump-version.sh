#!/usr/bin/env bash
# Set the version everywhere it is carried (docs/release.md, "Version bump"):
#   Cargo.toml and python/Cargo.toml ([package] version), python/pyproject.toml
#   ([project] version), Cargo.lock (both packages), and CHANGELOG.md ([Unreleased] becomes
#   [NEW] - today, with a fresh empty [Unreleased] above it).
# `--version` and the Software/sidecar tags follow from Cargo.toml (day2night::VERSION).
# The committed fixtures carry the Software tag, so they are regenerated too (skip with
# --no-fixtures, e.g. on a copy of the manifests only). tests/it/release_version.rs checks
# that every place agrees.
#   scripts/bump-version.sh 0.2.0 [--no-fixtures]        (ROOT=dir to work on another tree)
set -euo pipefail
new="${1:?usage: scripts/bump-version.sh NEW_VERSION [--no-fixtures]}"
fixtures=1
[ "${2:-}" = --no-fixtures ] && fixtures=0
if ! [[ "$new" =~ ^[0-9]+\.[0-9]+\.[0-9]+(-[0-9A-Za-z.]+)?$ ]]; then
  echo "bump-version: $new is not a SemVer version (e.g. 0.2.0)" >&2
  exit 2
fi
cd "${ROOT:-$(dirname "$0")/..}"
# The first `version = "..."` line of a file: [package] / [project] comes first in each.
set_first() {
  python3 - "$1" "$new" <<'PY'
import re, sys
path, new = sys.argv[1], sys.argv[2]
text = open(path, encoding="utf-8").read()
out, n = re.subn(r'(?m)^version = "[^"]*"', f'version = "{new}"', text, count=1)
if n != 1:
    sys.exit(f"bump-version: no version line in {path}")
open(path, "w", encoding="utf-8").write(out)
PY
}
set_first Cargo.toml
set_first python/Cargo.toml
set_first python/pyproject.toml
if [ -f Cargo.lock ]; then
  python3 - "$new" <<'PY'
import re, sys
new = sys.argv[1]
text = open("Cargo.lock", encoding="utf-8").read()
for name in ("day2night", "day2night-python"):
    text = re.sub(rf'(name = "{name}"\nversion = )"[^"]*"', rf'\1"{new}"', text)
open("Cargo.lock", "w", encoding="utf-8").write(text)
PY
fi
if [ -f CHANGELOG.md ]; then
  python3 - "$new" "$(date -u +%F)" <<'PY'
import sys
new, day = sys.argv[1], sys.argv[2]
text = open("CHANGELOG.md", encoding="utf-8").read()
if f"## [{new}]" in text:
    sys.exit(f"bump-version: CHANGELOG.md already has a section [{new}]")
if "## [Unreleased]\n" not in text:
    sys.exit("bump-version: CHANGELOG.md has no [Unreleased] section")
text = text.replace("## [Unreleased]\n", f"## [Unreleased]\n\n## [{new}] - {day}\n", 1)
open("CHANGELOG.md", "w", encoding="utf-8").write(text)
PY
fi
if [ "$fixtures" = 1 ]; then
  cargo run --quiet --release --example make_fixtures -- fixtures/
fi
echo "bump-version: $new"
