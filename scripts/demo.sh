#!/usr/bin/env bash
# Installs what is missing, builds tbs (Release) and runs the main job on the bundled sample:
# a summary of the sample spline and a table of surface points, normals and timings.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
tbs_install_deps
tbs_build tbs
tbs=build/cli/tbs
sample=samples/wave.tbs
out=${TBS_DEMO_OUT:-out/demo}
mkdir -p "$out"

echo "== tbs info $sample"
"$tbs" info "$sample" > "$out/info.json"
grep -E "^  \"(degree|units|vertices|triangles|edges|control_points|boundary_loops|holes|feature_edges)\"" "$out/info.json"
echo "  knot conditions:$(grep -m1 '"ok"' "$out/info.json" | sed 's/.*"ok": *//; s/,$//')"
echo "  continuity (lower bounds):$(grep -E '"(smooth_edges_min|features_at_most_c0)"' "$out/info.json" | tr -d '\n' | tr -s ' ')"
echo "   (full report: $out/info.json)"

# A 201 x 101 grid over the domain's bounding box, keeping the points inside the domain.
uv_grid() {
  awk 'BEGIN { for (j = 0; j <= 100; j++) for (i = 0; i <= 200; i++) printf "%.6f %.6f\n", 2*i/200, j/100 }'
}
uv_grid > "$out/grid.uv"
# Points in the hole are outside the domain: drop them (u in (1.25, 1.625), v in (0.375, 0.625)).
awk '!($1 > 1.25 && $1 < 1.625 && $2 > 0.375 && $2 < 0.625)' "$out/grid.uv" > "$out/points.uv"

start=$(date +%s.%N)
"$tbs" eval "$sample" --input "$out/points.uv" --normals > "$out/points.xyz"
end=$(date +%s.%N)
count=$(wc -l < "$out/points.xyz")

echo
echo "== tbs eval: $count points in $(awk -v a="$start" -v b="$end" 'BEGIN{printf "%.3f", b-a}') s (whole command)"
printf "%10s %10s | %10s %10s %10s | %8s %8s %8s\n" u v x y z nx ny nz
paste -d' ' "$out/points.uv" "$out/points.xyz" | awk 'NR % 2500 == 1 {
  printf "%10.4f %10.4f | %10.3f %10.3f %10.3f | %8.4f %8.4f %8.4f\n", $1, $2, $3, $4, $5, $6, $7, $8 }'
echo
echo "Surface points with normals: $out/points.xyz (x y z nx ny nz per line)"
