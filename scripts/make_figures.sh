#!/usr/bin/env bash
# Regenerates every docs/figures/NAME.dot into docs/figures/NAME.svg with Graphviz (Debian package
# graphviz, in scripts/setup.sh). The .svg files are committed beside their sources, so the docs read
# without Graphviz; run this after editing a .dot and commit both.
set -euo pipefail
cd "$(dirname "$0")/.."

command -v dot >/dev/null || { echo "make_figures: 'dot' not found (apt-get install graphviz)" >&2; exit 1; }
shopt -s nullglob
count=0
for source in docs/figures/*.dot; do
  dot -Tsvg "$source" -o "${source%.dot}.svg"
  echo "make_figures: ${source%.dot}.svg"
  count=$((count + 1))
done
[ "$count" -gt 0 ] || echo "make_figures: no docs/figures/*.dot" >&2
