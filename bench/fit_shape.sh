#!/usr/bin/env bash
# Fairness of the fits, for docs/benchmarks.md#fairness-between-the-points: every RawScan input
# of the tests (Debian's libcgal-demo, no parameters) fitted by `tbs fit --tolerance 1e-3`, then
# the dense synthetic scans (bench/make_synthetic.py) and the bracket sample at the defaults.
# Prints markdown tables: points fitted (measured + guides), control points (also per measured
# point: the issue-19 budget is 1 for a mesh), folds, max_stretch, max error, time.
# Extra arguments go to every `tbs fit` (e.g. --smoothness 0 for the figures without it).
#
#   bench/fit_shape.sh [BUILD_DIR] [-- FIT_OPTIONS...]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="$here/build"
if [ $# -gt 0 ] && [ "$1" != "--" ]; then build="$1"; shift; fi
[ "${1:-}" = "--" ] && shift
tbs="$build/cli/tbs"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
tar xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$work" data/meshes data/points_3

row() {  # name json [start time of the command, seconds since the epoch]
  python3 - "$1" "$2" "${3:-}" <<'PY'
import json, sys, time
r = json.load(open(sys.argv[2]))
wall = " (%.0f wall)" % (time.time() - float(sys.argv[3])) if sys.argv[3] else ""
guides = r.get("guide_points", 0)
measured = r["points"] - guides
points = f"{measured:,}" + (f" + {guides:,} guides" if guides else "")
print("| %s | %s | %s | %s | %.2f | %d | %.3g | %.3e | %s | %.1f" % (
    sys.argv[1], points, f"{r['domain_triangles']:,}", f"{r['control_points']:,}", r["control_points"] / measured,
    r["folds"], r["max_stretch"], r["max_error"], "yes" if r["converged"] else "no (" + r["stop_reason"] + ")",
    r["seconds"]) + wall + " |")
PY
}
header() {
  echo "| input | points fitted | domain triangles | control points | per measured point | folds | max_stretch | max error | converged | fit s |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
}

echo "Raw scans (tbs fit IN --tolerance 1e-3 $*):"
echo
header
for f in meshes/mask_cone.off meshes/mesh_with_border.off meshes/cylinder.off points_3/poste_france.xyz \
         meshes/patch-20.off meshes/sphere966.off meshes/head.off meshes/lion.off; do
  name="$(basename "$f")"
  out="$work/${name%.*}"
  start=$(date +%s.%N)
  if "$tbs" fit "$work/data/$f" -o "$out.tbs" --tolerance 1e-3 --report "$out.json" -q "$@" > /dev/null 2> "$out.err"; then
    row "$name" "$out.json" "$start"
  else
    echo "| $name | failed: $(head -c 200 "$out.err" | tr '\n' ' ') | | | | | | | |"
  fi
done
echo
echo "Dense scans (tbs fit IN $*):"
echo
header
for kind in smooth creased holes; do
  for n in 25000 50000 200000; do
    scan="$work/$kind-$n.ply"
    python3 "$here/bench/make_synthetic.py" "$n" "$kind" "$scan" > /dev/null
    "$tbs" fit "$scan" -o "$work/s.tbs" --report "$work/s.json" -q "$@" > /dev/null
    row "$kind $n" "$work/s.json"
  done
done
"$tbs" fit "$here/samples/bracket.ply" -o "$work/s.tbs" --report "$work/s.json" -q "$@" > /dev/null
row "bracket" "$work/s.json"
