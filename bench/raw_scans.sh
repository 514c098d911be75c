#!/usr/bin/env bash
# Raw scans (no parameters) from Debian's libcgal-demo, for docs/benchmarks.md: each is
# parameterized and fitted by `tbs fit --tolerance 1e-3`, then written as STEP triangle
# patches (`--faces triangles`, CAD tolerance 1e-3, angle tolerance 20 degrees, at most 5000
# patches: the compact patch count of docs/benchmarks.md#raw-scans; CAD_OPTS overrides them;
# given up after STEP_TIMEOUT seconds, 300 by default).
# Prints a markdown table: topology, what the parameterization did, its distortion, the fit,
# the STEP patches and normal deviation, and the wall times and peak memory of the fit and of
# the STEP export.
#
#   bench/raw_scans.sh [BUILD_DIR]      (default: build)
#   STEP_TIMEOUT=0 bench/raw_scans.sh   skips the STEP exports
#   CAD_OPTS="--cad-tolerance 1e-4 --angle-tolerance 20" bench/raw_scans.sh
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build}"
tbs="$build/cli/tbs"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
tar xzf /usr/share/doc/libcgal-dev/data.tar.gz -C "$work" data/meshes data/points_3

echo "| input | points | topology (chosen component) | parameterization | angle / area distortion (mean, max) | fit points | domain triangles | control points | max error | converged | fit s | fit MB | STEP patches | STEP normal dev. (deg) | STEP s | STEP MB |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in meshes/mask_cone.off meshes/mesh_with_border.off meshes/cylinder.off meshes/head.off \
         meshes/lion.off meshes/patch-20.off meshes/fandisk.off meshes/sphere966.off \
         points_3/radar.xyz points_3/poste_france.xyz points_3/kitten.xyz; do
  name="$(basename "$f")"
  in="$work/data/$f" out="$work/${name%.*}"
  if ! /usr/bin/time -f "%e %M" -o "$out.fit.time" "$tbs" fit "$in" -o "$out.tbs" --tolerance 1e-3 \
       --report "$out.json" -q > "$out.fit.txt" 2> "$out.err"; then
    echo "| $name | | | refused: $(head -c 300 "$out.err" | tr '\n' ' ' | sed 's/|/\\|/g') | | | | | | | | | | | | |"
    continue
  fi
  if [ "${STEP_TIMEOUT:-300}" = 0 ]; then
    echo "skipped 0" > "$out.step.time"
  elif ! /usr/bin/time -f "%e %M" -o "$out.step.time" timeout "${STEP_TIMEOUT:-300}" "$tbs" convert "$out.tbs" "$out.step" \
       ${CAD_OPTS:---faces triangles --cad-tolerance 1e-3 --angle-tolerance 20 --max-patches 5000} -q > "$out.step.txt" 2>&1; then
    echo "gave up 0" > "$out.step.time"
  fi
  python3 - "$name" "$out" <<'PY'
import json, sys
name, out = sys.argv[1], sys.argv[2]
r = json.load(open(out + ".json"))
p = r["parameterization"]
t = p["component_topology"]
fit_s, fit_kb = open(out + ".fit.time").read().split()
step = open(out + ".step.time").read().split()
step_s, step_kb = step[-2], step[-1]
if step[0] == "gave":
    step_s, step_kb = "gave up", "0"
if step[0] == "skipped":
    step_s, step_kb = "-", "0"
patches, ndev = "-", "-"
try:
    for line in open(out + ".step.txt"):
        if line.startswith("content "):  # "content  N triangle patches, ..." or "N region faces, ..."
            patches = line.split()[1]
        if line.startswith("max normal dev."):
            ndev = line.split()[3]
except OSError:
    pass
how = [p["input"]]
if p["input"] == "point cloud":
    how.append("%d faces reconstructed" % p["reconstructed_faces"])
if p["seam_edges"]:
    how.append("seam of %d edges" % p["seam_edges"])
how.append(p["method"] + (" (" + p["fallback_reason"] + ")" if p["fallback_reason"] else ""))
if p["subdivisions"]:
    how.append("%d x subdivided" % p["subdivisions"])
topo = "%d of %d components; %d boundary loops, genus %d" % (p["component"], p["topology"]["components"], t["boundary_loops"], t["genus"])
a, b = p["angle_distortion"], p["area_distortion"]
print("| %s | %d | %s | %s | %.3f, %.3g / %.3g, %.3g | %d | %d | %d | %.2e | %s | %s | %.0f | %s | %s | %s | %.0f |" % (
    name, p["input_points"], topo, "; ".join(how), a["mean"], a["max"], b["mean"], b["max"], r["points"],
    r["domain_triangles"], r["control_points"], r["max_error"], "yes" if r["converged"] else "no (" + r["stop_reason"] + ")",
    fit_s, int(fit_kb) / 1024, patches, ndev, step_s, int(step_kb) / 1024 if int(step_kb) else 0))
PY
done
