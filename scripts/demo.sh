#!/usr/bin/env bash
# Installs what is missing, builds tbs (Release) and runs the main job on the bundled sample:
# fits one triangular B-spline to the scan samples/bracket.ply (a folded sheet with a 60 degree
# crease and a hole, 40,933 points with parameters), prints the report table, checks the result
# with `tbs info`, samples the surface across the crease, writes it as STEP, IGES and glTF,
# and writes the error map of the scan as OpenEXR with a PNG preview.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
tbs_install_deps
tbs_build tbs
tbs=build/cli/tbs
scan=samples/bracket.ply
out=${TBS_DEMO_OUT:-out/demo}
mkdir -p "$out"

echo "== tbs fit $scan -o $out/bracket.tbs --units mm --report $out/report.json"
"$tbs" fit "$scan" -o "$out/bracket.tbs" --units mm --report "$out/report.json"

echo
echo "== time per stage (s), from $out/report.json"
tr -d '\n ' < "$out/report.json" | sed 's/.*"stage_seconds":{\([^}]*\)}.*/\1/' | tr ',' '\n' |
  awk -F: '{ gsub(/"/, "", $1); printf "  %-8s %8.3f\n", $1, $2 }'

echo
echo "== tbs info $out/bracket.tbs"
"$tbs" info "$out/bracket.tbs" > "$out/info.json"
grep -E "^  \"(degree|units|vertices|triangles|control_points|holes|feature_edges)\"" "$out/info.json"
echo "  knot conditions ok:$(grep -m1 '"ok"' "$out/info.json" | sed 's/.*"ok": *//; s/,$//')"
echo "  feature edges at most C^0:$(grep -m1 '"features_at_most_c0"' "$out/info.json" | sed 's/.*: *//; s/,$//')"

# Across the crease (u = 0.55): the normal turns by the fold angle (60 degrees).
echo
echo "== surface normals just left and right of the crease u = 0.55"
printf '%s\n' "0.5499999 0.2" "0.5500001 0.2" "0.5499999 0.9" "0.5500001 0.9" > "$out/crease.uv"
"$tbs" eval "$out/bracket.tbs" --input "$out/crease.uv" --normals > "$out/crease.xyz"
paste -d' ' "$out/crease.uv" "$out/crease.xyz" | awk '
  { printf "  u %.7f v %.1f -> x %8.3f y %8.3f z %8.3f  n (%7.4f %7.4f %7.4f)\n", $1, $2, $3, $4, $5, $6, $7, $8
    if (NR % 2 == 1) { x = $6; y = $7; z = $8 }
    else { d = x * $6 + y * $7 + z * $8; printf "  normal turns by %.1f degrees\n", atan2(sqrt(1 - d * d), d) * 57.29578 } }'
echo
echo "== tbs convert $out/bracket.tbs $out/bracket.step (and .igs): CAD files through OpenCASCADE"
"$tbs" convert "$out/bracket.tbs" "$out/bracket.step" --quiet
"$tbs" convert "$out/bracket.tbs" "$out/bracket.igs" --quiet | tail -n +2 | head -2
echo
echo "== tbs convert $out/bracket.tbs $out/bracket.glb --points $scan --color-by error: a glTF mesh for viewers, coloured by the error"
"$tbs" convert "$out/bracket.tbs" "$out/bracket.glb" --points "$scan" --color-by error --quiet
echo
echo "== tbs convert $out/bracket.tbs $out/bracket.exr --points $scan: the error map (+ .png preview)"
"$tbs" convert "$out/bracket.tbs" "$out/bracket.exr" --points "$scan" --quiet
echo
echo "Outputs in $out: bracket.tbs (the spline), report.json (fit report), info.json,"
echo "bracket.step and bracket.igs (the surface as B-spline faces in one shell), bracket.glb (mesh coloured by the error),"
echo "bracket.exr (error map and geometry image) and bracket.png (its preview)"
