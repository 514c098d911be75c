#!/usr/bin/env bash
# Converter figures for docs/benchmarks.md: fits the bundled scan with about 1,000 domain
# triangles at degrees 2, 3 and 4, then times exact Bezier extraction and compact CAD patches
# on each fit. Prints markdown tables.
#
#   bench/convert_bench.sh [BUILD_DIR]      (default: build)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build}"
tbs="$build/cli/tbs"
bench="$build/bench/tbs_convert_bench"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

files=()
for degree in 2 3 4; do
  "$tbs" fit "$here/samples/bracket.ply" -o "$work/bracket-d$degree.tbs" --degree "$degree" \
    --triangles 1000 > /dev/null 2>&1
  files+=("$work/bracket-d$degree.tbs")
done
cd "$work"
echo "Exact extraction:"
echo
"$bench" "${files[@]##*/}"
echo
echo "Compact CAD patches (tolerance 1e-6 of the model size, angle tolerance 1 degree):"
"$bench" "${files[@]##*/}" --no-extract --cad-degrees 3,5,7
echo
echo "Compact CAD patches, looser tolerances (cubic fit, patch degree 5):"
for tol in 1e-5 1e-4; do
  "$bench" "bracket-d3.tbs" --no-extract --cad-degrees 5 --cad-tolerance "$tol" | tail -n 1 | sed "s/\$/ tolerance $tol/"
done
