#!/usr/bin/env bash
# What free knots gain, for docs/benchmarks.md#free-knots: every input fitted with fixed knots
# (--knot-sweeps 0) and with free knots (1 and 3 passes per round), all else at the defaults.
#   - "to the tolerance": refinement runs until the tolerance (1e-3); the control points needed.
#   - "equal control points": --max-iterations 0 (the initial domain, no refinement); the
#     errors reached with the same control points.
# Inputs: bench/make_synthetic.py's wavy and creased 50k scans (creased also from a coarse
# start, --triangles 16, since it meets the tolerance on its default initial domain, where the
# knots are not searched), and two RawScan meshes of Debian's libcgal-demo.
#
#   bench/knot_gain.sh [BUILD_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build}"
tbs="$build/cli/tbs"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
tar xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$work" data/meshes
python3 "$here/bench/make_synthetic.py" 50000 wavy "$work/wavy.ply" > /dev/null
python3 "$here/bench/make_synthetic.py" 50000 creased "$work/creased.ply" > /dev/null

fit() {  # label input mode extra-options...
  local label="$1" input="$2" mode="$3"
  shift 3
  local cells=()
  for sweeps in 0 1 3; do
    "$tbs" fit "$input" -o "$work/k.tbs" --report "$work/k.json" -q --knot-sweeps "$sweeps" "$@" > /dev/null
    cells+=("$(python3 - "$work/k.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("%s cp, max %.2e, RMS %.2e, %d folds, %.1f s" % (f"{r['control_points']:,}", r["max_error"], r["rms_error"],
                                                   r["folds"], r["seconds"]))
PY
)")
  done
  echo "| $label | $mode | ${cells[0]} | ${cells[1]} | ${cells[2]} |"
}

echo "| input | compared | fixed knots (--knot-sweeps 0) | free, 1 pass per round | free, 3 passes per round |"
echo "|---|---|---|---|---|"
fit "wavy 50k" "$work/wavy.ply" "to the tolerance"
fit "wavy 50k" "$work/wavy.ply" "equal control points" --max-iterations 0
fit "creased 50k" "$work/creased.ply" "to the tolerance"
fit "creased 50k, --triangles 16" "$work/creased.ply" "to the tolerance" --triangles 16
fit "creased 50k, --tolerance 1e-4" "$work/creased.ply" "equal control points" --max-iterations 0 --tolerance 1e-4
fit "mask_cone.off" "$work/data/meshes/mask_cone.off" "to the tolerance"
fit "mask_cone.off" "$work/data/meshes/mask_cone.off" "equal control points" --max-iterations 0
fit "patch-20.off" "$work/data/meshes/patch-20.off" "to the tolerance"
