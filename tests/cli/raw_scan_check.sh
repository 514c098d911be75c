#!/usr/bin/env bash
# A raw scan from Debian's libcgal-demo (no parameters) goes through `tbs fit --tolerance 1e-3`:
# it is parameterized, the fit converges, the report says how it was parameterized. Then the
# fit is converted to CAD files, each checked by OpenCASCADE before writing (tbs refuses an
# invalid shell with exit 5), and the region-face files read back by FreeCAD
# (freecad_shape_check.py: valid, the reported faces, one shell per chart and one free loop per
# boundary loop; over an atlas one shell, a solid if it is closed).
# Every point the fit counts as fitted evaluates through `tbs eval` (fitted_points_check.py).
# No domain triangle folds (but on lion, issue 19), and max_stretch is at most 20.
#   raw_scan_check.sh TBS_EXE WORK_DIR DATA_FILE
#     DATA_FILE inside the tarball, e.g. data/meshes/head.off
# Exports: region faces at the default CAD tolerance as STEP and IGES, triangle patches (CAD
# tolerance 1e-3, angle 20), and the exact pieces (one face each; lion.off's 202,473 take about
# 2 minutes and 6 GB: docs/benchmarks.md#cad-export).
set -euo pipefail
tbs="$1" work="$2" file="$3"
here="$(cd "$(dirname "$0")" && pwd)"
tarball=/usr/share/doc/libcgal-dev/data.tar.gz
if [ ! -f "$tarball" ]; then
  echo "libcgal-demo is not installed (scripts/test.sh installs it)" >&2
  exit 1
fi
mkdir -p "$work"
tar xzf "$tarball" -C "$work" "$file"
name="$(basename "$file")"
out="$work/${name%.*}"
"$tbs" fit "$work/$file" -o "$out.tbs" --tolerance 1e-3 --report "$out.json" --keep-points --quiet | tee "$out.txt"
# Every point the fit counts evaluates through `tbs eval` at the (u, v) it was fitted at.
python3 "$here/fitted_points_check.py" "$tbs" "$out.tbs" "$out.json"
python3 - "$out.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
p = r["parameterization"]
assert r["converged"], "the fit did not converge: " + r["stop_reason"]
assert r["max_error"] <= r["tolerance"] * (1 + 1e-9), (r["max_error"], r["tolerance"])
assert p["method"] in ("LSCM", "LSCM, areas relaxed", "mean value (circular boundary)", "charts (LSCM)"), p["method"]
assert p["component_topology"]["genus"] == 0
# A closed surface is cut into charts (an atlas), and so is an open one whose one flattening
# would stretch a spline over it more than 4 times; the fit then reports the atlas, and its
# seams close far inside the tolerance.
closed = p["component_topology"]["boundary_loops"] == 0
assert r["closed"] == closed and r["genus"] == 0, (r["closed"], r["genus"])
assert (p["charts"] > 1) == (p["method"] == "charts (LSCM)") == (r["seams"] > 0), (p["charts"], p["method"], r["seams"])
if closed:
    assert p["charts"] > 1, "a closed surface flattened as one chart"
if r["seams"] > 0:
    assert r["seam_gap"] <= 0.1 * r["tolerance"], "seam gap %.3g" % r["seam_gap"]
    assert r["seam_samples_outside"] == 0, r["seam_samples_outside"]
# No folded domain triangle, except on lion, where issue 19 is still open (6 folds since its
# flattening is relaxed toward equal areas, 28 before: docs/benchmarks.md). sphere966 folded in 13
# triangles at its seam ends until the outline kept the seam's notches open, poste_france.xyz
# in 16 until faces spanning gaps in the cloud were removed (2026-12-06).
known = {"lion.json"}
if sys.argv[1].split("/")[-1] not in known:
    assert r["folds"] == 0, "%d folded domain triangles" % r["folds"]
# Issue 19's bound on the largest |F_u|, |F_v| (times the domain's diameter, over the model
# size); head (28.8) and lion (42.6) were above it until their flattenings were relaxed.
assert r["max_stretch"] <= 20, "max_stretch %.3g" % r["max_stretch"]
print("parameterized by %s, angle distortion %.3f, area distortion %.3f; converged, max error %.3g, %d folds, max_stretch %.3g"
      % (p["method"], p["angle_distortion"]["mean"], p["area_distortion"]["mean"], r["max_error"], r["folds"], r["max_stretch"]))
PY
relaxed=(--cad-tolerance 1e-3 --angle-tolerance 20)
"$tbs" convert "$out.tbs" "$out.step" --report "$out.step.json" | tee "$out.step.txt"
"$tbs" convert "$out.tbs" "$out.igs" --quiet
cad=("$out.step" "$out.igs")
/usr/bin/python3 "$here/freecad_shape_check.py" "$out.tbs" "$out.step.json" "${cad[@]}"
"$tbs" convert "$out.tbs" "$out-triangles.step" --faces triangles "${relaxed[@]}" --quiet
test -s "$out-triangles.step"
# tbs checks every shape with BRepCheck before writing it and refuses an invalid one (exit 5).
"$tbs" convert "$out.tbs" "$out-exact.step" --exact --triangle-patch degenerate --quiet
test -s "$out-exact.step"
rm -f "$out"*.step "$out"*.igs
