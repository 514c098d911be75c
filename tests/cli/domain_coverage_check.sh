#!/usr/bin/env bash
# The fit and `tbs eval` agree on what the domain covers: every point a fit counts as fitted
# evaluates through `tbs eval` after the .tbs round trip (fitted_points_check.py), for
#   - bare points placed on, and within 1e-9 of, the outer boundary and the loops of two holes
#     (a square hole and a round one), fitted without faces;
#   - the same points with the outer boundary on an ellipse (round loops everywhere);
#   - synthetic smooth, creased and holed scans (bench/make_synthetic.py);
#   - the bracket sample.
# The RawScan tests (raw_scan_check.sh) check the raw scans the same way.
#   domain_coverage_check.sh TBS_EXE SOURCE_DIR WORK_DIR
set -euo pipefail
tbs="$1" src="$2" work="$3"
here="$(cd "$(dirname "$0")" && pwd)"
rm -rf "$work"
mkdir -p "$work"

# x y z u v lines: random points in the region, then points on each loop and 1e-9 to either side.
python3 - "$work" <<'PY'
import math, random, sys
work = sys.argv[1]
def inside(kind, u, v):
    if kind == "ellipse" and ((u - 0.5) / 0.5) ** 2 + ((v - 0.5) / 0.35) ** 2 > 1:
        return False
    if 0.15 <= u <= 0.35 and 0.4 <= v <= 0.6:          # square hole
        return False
    return math.hypot(u - 0.68, v - 0.5) >= 0.12        # round hole
def loops(kind):
    # (point on the loop, outward normal of the region there) along each boundary loop
    out = []
    for k in range(400):
        t = 2 * math.pi * k / 400
        if kind == "ellipse":
            out.append(((0.5 + 0.5 * math.cos(t), 0.5 + 0.35 * math.sin(t)),
                        (math.cos(t) / 0.5, math.sin(t) / 0.35)))
        out.append(((0.68 + 0.12 * math.cos(t), 0.5 + 0.12 * math.sin(t)), (-math.cos(t), -math.sin(t))))
    for k in range(100):
        s = k / 100
        for (u, v), n in [((0.15 + 0.2 * s, 0.4), (0, 1)), ((0.35, 0.4 + 0.2 * s), (-1, 0)),
                          ((0.35 - 0.2 * s, 0.6), (0, -1)), ((0.15, 0.6 - 0.2 * s), (1, 0))]:
            out.append(((u, v), n))
        if kind == "square":
            for (u, v), n in [((s, 0.0), (0, -1)), ((1.0, s), (1, 0)), ((1 - s, 1.0), (0, 1)), ((0.0, 1 - s), (-1, 0))]:
                out.append(((u, v), n))
    return out
for kind in ("square", "ellipse"):
    rng = random.Random(7)
    pts = []
    while len(pts) < 30000:
        u, v = rng.random(), rng.random()
        if inside(kind, u, v):
            pts.append((u, v))
    for (u, v), (nu, nv) in loops(kind):
        ln = math.hypot(nu, nv)
        for off in (0.0, 1e-9, -1e-9):
            pts.append((u + off * nu / ln, v + off * nv / ln))
    with open(f"{work}/{kind}.xyz", "w") as f:
        for u, v in pts:
            f.write("%.17g %.17g %.17g %.17g %.17g\n" % (u, v, 0.1 * math.sin(3 * u) * math.cos(2 * v), u, v))
PY

check() {  # NAME SCAN [fit options]
  local name="$1" scan="$2"
  shift 2
  "$tbs" fit "$scan" -o "$work/$name.tbs" --keep-points --report "$work/$name.json" --quiet "$@" > /dev/null
  printf '%s: ' "$name"
  python3 "$here/fitted_points_check.py" "$tbs" "$work/$name.tbs" "$work/$name.json"
}
check square "$work/square.xyz" --tolerance 1e-3
check ellipse "$work/ellipse.xyz" --tolerance 1e-3
for kind in smooth creased holes; do
  python3 "$src/bench/make_synthetic.py" 20000 "$kind" "$work/$kind.ply" 3
  check "$kind" "$work/$kind.ply" --tolerance 1e-3
done
check bracket "$src/samples/bracket.ply" --units mm
