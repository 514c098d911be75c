#!/usr/bin/env bash
# Memory benchmark: peak resident memory of `tbs fit` against the number of points, the degree
# and the number of control points, next to the estimate the fit checks against --max-memory
# (estimate_fit_memory(), calibrated on these rows). Prints a Markdown table.
#
#   bench/memory_bench.sh [quick|full]     (default full: adds 100k points on 20,000 triangles and 400k points at
#                                          degrees 2 to 4)
#
# Only memory is reported: it does not depend on what else the machine runs.
#
# Needs a Release build (scripts/test.sh or scripts/demo.sh) and GNU time (/usr/bin/time).
set -euo pipefail
cd "$(dirname "$0")/.."
tbs=build/cli/tbs
[ -x "$tbs" ] || { echo "build tbs first (scripts/demo.sh)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs GNU time: apt-get install time" >&2; exit 1; }
mode=${1:-full}
work=${TBS_BENCH_DIR:-out/bench}
mkdir -p "$work"
for n in 100000 400000; do
  [ -f "$work/smooth-$n.ply" ] || python3 bench/make_synthetic.py "$n" smooth "$work/smooth-$n.ply"
done

# One fit round on the initial domain (--max-iterations 0), so that the control points are
# the ones the domain size gives; --triangles varies them at a fixed number of points.
row() {  # points degree triangles(0 = default)
  local points=$1 degree=$2 triangles=$3 extra=() rep="$work/memory.json"
  [ "$triangles" -gt 0 ] && extra=(--triangles "$triangles")
  /usr/bin/time -f "%M" -o "$work/mem.txt" "$tbs" fit "$work/smooth-$points.ply" -o "$work/memory.tbs" -q \
    --degree "$degree" --max-iterations 0 --max-memory 1T --report "$rep" "${extra[@]}" > /dev/null
  python3 - "$rep" "$(cat "$work/mem.txt")" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
peak = int(sys.argv[2]) / 1024
est = r["memory_estimate"] / 2**20
print(f"| {r['points']:,} | {r['degree']} | {r['domain_triangles']:,} | {r['control_points']:,} | "
      f"{peak:.0f} | {est:.0f} | {est / peak:.2f} |")
PY
}

echo "| points | degree | domain triangles | control points | peak memory (MiB) | estimate (MiB) | estimate / peak |"
echo "|---|---|---|---|---|---|---|"
for d in 2 3 4 5; do row 100000 "$d" 0; done
for t in 2000 8000; do row 100000 3 "$t"; done
row 100000 4 2000
if [ "$mode" = full ]; then
  row 100000 3 20000
  for d in 2 3 4; do row 400000 "$d" 0; done
fi
