#!/usr/bin/env bash
# Where the control-point solve spends its time: fits of the large synthetic scans of issue 20
# (bench/make_synthetic.py), each row with the report's `solve_stages` (docs/fit.md): solves,
# wall seconds of pattern / basis rows (thread-seconds) / assembly / analysis /
# factorization / solve, the conjugate-gradient iterations, the factorised matrix, and the
# peak memory of the whole fit. Prints a Markdown table for docs/benchmarks.md.
#
#   bench/solve_profile.sh [quick|full]   (default full: the four rows of issue 20, about 2
#                                          minutes on 2 cores; quick: 200k points only)
#
# Needs a Release build (scripts/test.sh or scripts/demo.sh) and GNU time (/usr/bin/time).
set -euo pipefail
cd "$(dirname "$0")/.."
tbs=${TBS:-build/cli/tbs}
[ -x "$tbs" ] || { echo "build tbs first (scripts/demo.sh)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs GNU time: apt-get install time" >&2; exit 1; }
mode=${1:-full}
work=${TBS_BENCH_DIR:-out/bench}
mkdir -p "$work"

cases=("smooth 200000 3" "creased 200000 3" "creased 200000 4")
[ "$mode" = full ] && cases=("smooth 1000000 3" "creased 1000000 3" "smooth 1000000 4" "creased 200000 4")

echo "| scan | points | degree | control points | max error | converged | fit s | solve s | solves | pattern / basis rows / assembly / analysis / factorization / solve s | CG iterations | factorised: rows, nonzeros | peak MB |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  read -r kind points degree <<< "$c"
  input="$work/$kind-$points.ply"
  [ -f "$input" ] || python3 bench/make_synthetic.py "$points" "$kind" "$input"
  rep="$work/solve-$kind-$points-$degree.json"
  /usr/bin/time -f "%M" -o "$work/mem.txt" "$tbs" fit "$input" -o "$work/out.tbs" -q \
    --degree "$degree" --report "$rep" > /dev/null
  python3 - "$rep" "$kind" "$points" "$degree" "$(cat "$work/mem.txt")" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
kind, points, degree, kb = sys.argv[2:]
s = r["solve_stages"]
parts = " / ".join("%.1f" % s[k] for k in ("pattern", "basis_rows", "assembly", "analysis", "factorization", "solve"))
print("| %s | {:,} | %s | {:,} | %.2e | %s | %.1f | %.1f | %d | %s | %d | {:,}, {:,} | %d |".format(
    int(points), r["control_points"], s["unknowns"], s["nonzeros"])
      % (kind, degree, r["max_error"], "yes" if r["converged"] else "no", r["seconds"],
         dict(r["stage_seconds"])["solve"], s["solves"], parts, s["cg_iterations"], int(kb) // 1024))
EOF
done
