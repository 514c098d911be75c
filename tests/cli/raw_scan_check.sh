#!/usr/bin/env bash
# A raw scan from Debian's libcgal-demo (no parameters) goes through `tbs fit --tolerance 1e-3`:
# it is parameterized, the fit converges, the report says how it was parameterized, and the
# result is written as STEP (one shell, checked by OpenCASCADE before writing).
#   raw_scan_check.sh TBS_EXE WORK_DIR DATA_FILE
#     DATA_FILE inside the tarball, e.g. data/meshes/head.off
# The STEP export uses --cad-tolerance 1e-3 --angle-tolerance 20 --max-patches 5000, which
# keeps OpenCASCADE's sewing within test time (the defaults, 1e-6 and 1 degree, take minutes on
# these fits; docs/benchmarks.md#raw-scans has the figures at 1e-4).
set -euo pipefail
tbs="$1" work="$2" file="$3"
tarball=/usr/share/doc/libcgal-dev/data.tar.gz
if [ ! -f "$tarball" ]; then
  echo "libcgal-demo is not installed (scripts/test.sh installs it)" >&2
  exit 1
fi
mkdir -p "$work"
tar xzf "$tarball" -C "$work" "$file"
name="$(basename "$file")"
out="$work/${name%.*}"
"$tbs" fit "$work/$file" -o "$out.tbs" --tolerance 1e-3 --report "$out.json" --quiet | tee "$out.txt"
python3 - "$out.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
p = r["parameterization"]
assert r["converged"], "the fit did not converge: " + r["stop_reason"]
assert r["max_error"] <= r["tolerance"] * (1 + 1e-9), (r["max_error"], r["tolerance"])
assert p["method"] in ("LSCM", "mean value (circular boundary)"), p["method"]
assert p["component_topology"]["genus"] == 0
print("parameterized by %s, angle distortion %.3f, area distortion %.3f; converged, max error %.3g"
      % (p["method"], p["angle_distortion"]["mean"], p["area_distortion"]["mean"], r["max_error"]))
PY
"$tbs" convert "$out.tbs" "$out.step" --cad-tolerance 1e-3 --angle-tolerance 20 --max-patches 5000 \
  | tee "$out.step.txt"
grep -q " 1 shell," "$out.step.txt"
test -s "$out.step"
