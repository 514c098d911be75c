#!/usr/bin/env bash
# Fit benchmark: the paper's Table 1 columns, time per stage and peak memory for synthetic
# scans (bench/make_synthetic.py) and the bundled sample. Prints a Markdown table.
#
#   bench/fit_bench.sh [quick|full]     (default full: adds 200k and 1M points)
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

cases=(
  "smooth 25000 3" "smooth 25000 4" "smooth 50000 3" "smooth 50000 4"
  "creased 50000 3" "holes 50000 3" "wavy 50000 3" "wavy 50000 4"
)
[ "$mode" = full ] && cases+=("smooth 200000 3" "smooth 1000000 3")

row() {  # name points degree input
  local name=$1 points=$2 degree=$3 input=$4 rep="$work/$1-$2-$3.json"
  /usr/bin/time -f "%M" -o "$work/mem.txt" "$tbs" fit "$input" -o "$work/out.tbs" -q \
    --degree "$degree" --report "$rep" > /dev/null
  python3 - "$rep" "$name" "$(cat "$work/mem.txt")" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
s = r["stage_seconds"]
print(f"| {sys.argv[2]} | {r['points']:,} | {r['degree']} | {r['domain_triangles']:,} | "
      f"{r['control_points']:,} | {r['max_error']:.2e} | {r['rms_error']:.2e} | "
      f"{'yes' if r['converged'] else 'no'} | {r['seconds']:.1f} | "
      f"{s['normals']:.1f} / {s['domain']:.1f} / {s['solve']:.1f} / {s['knots']:.1f} / {s['error']:.1f} | "
      f"{int(sys.argv[3]) / 1024:.0f} |")
EOF
}

echo "| scan | points | degree | domain triangles | control points | max error | RMS error | converged | time (s) | normals / domain / solve / knots / error (s) | peak memory (MB) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
row "bracket (sample mesh)" 40933 3 samples/bracket.ply
for c in "${cases[@]}"; do
  read -r kind points degree <<< "$c"
  file="$work/$kind-$points.ply"
  [ -f "$file" ] || python3 bench/make_synthetic.py "$points" "$kind" "$file"
  row "$kind (bare points)" "$points" "$degree" "$file"
done
