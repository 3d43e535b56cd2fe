#!/usr/bin/env bash
# Regenerates the generated dynamics sources (the closed-form Lagrange model,
# scripts/generate_lagrange.py, and the unrolled RNEA and CRBA,
# scripts/generate_recursive.py) into a temporary directory and fails if they
# differ from the committed ones (models/dynamics/generated/).
# Uses Debian's interpreter and SymPy, which generated the committed files.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
/usr/bin/python3 scripts/generate_lagrange.py --out "$tmp"
/usr/bin/python3 scripts/generate_recursive.py --out "$tmp"
if ! diff -u models/dynamics/generated "$tmp" > "$tmp.diff"; then
  head -40 "$tmp.diff"
  echo "check_generated: models/dynamics/generated/ is not what scripts/generate_lagrange.py" \
       "and scripts/generate_recursive.py produce; regenerate with /usr/bin/python3 on each and commit" >&2
  rm -f "$tmp.diff"
  exit 1
fi
rm -f "$tmp.diff"
echo "check_generated: models/dynamics/generated/ is current"
