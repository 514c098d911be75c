#!/usr/bin/env python3
"""FreeCAD (Debian's freecad-python3) reads a STEP or IGES file that `tbs convert` wrote and
finds what its report says: a valid shape, the reported number of faces, and
- without an atlas: one shell per chart of the spline's domain (its edge-connected components),
  and free edges forming one closed loop per boundary loop of the domain (each chart's outer
  boundary and holes);
- over an atlas (the fit cut the surface into charts glued along seams; the raw scans here are
  one surface each): one shell, one solid if the atlas is closed (no free edge), else free
  edges forming closed loops, as many as the report's free_loops.

usage: freecad_shape_check.py SPLINE.tbs REPORT.json CAD_FILE [CAD_FILE...]
  REPORT.json: `tbs convert --report` of the first file; every file must hold the same faces.
Exit 0 when every check passes, 1 otherwise (each check is printed).
"""
import json
import os
import sys

for lib in ("/usr/lib/freecad-python3/lib", "/usr/lib/freecad/lib"):
    if os.path.isdir(lib):
        sys.path.append(lib)
import FreeCAD  # noqa: E402,F401  (FreeCAD before Part)
import Part  # noqa: E402

spline, report_path = sys.argv[1:3]
files = sys.argv[3:]
report = json.load(open(report_path))
tbs = json.load(open(spline))
domain, atlas = tbs["domain"], tbs.get("atlas", {})
loops = len(domain["boundary_loops"])
# The charts: triangles joined across shared edges.
parent = list(range(len(domain["triangles"])))


def find(x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


first = {}
for t, tri in enumerate(domain["triangles"]):
    for k in range(3):
        e = tuple(sorted((tri[k], tri[(k + 1) % 3])))
        if e in first:
            parent[find(t)] = find(first[e])
        else:
            first[e] = t
charts = len({find(t) for t in range(len(parent))})
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)


for path in files:
    name = os.path.basename(path)
    shape = Part.Shape()
    shape.read(path)
    check(shape.isValid(), f"{name}: FreeCAD finds the shape valid")
    check(len(shape.Faces) == report["faces"], f"{name}: {len(shape.Faces)} faces read, {report['faces']} written")
    if atlas.get("seams"):
        check(len(shape.Shells) == 1, f"{name}: {len(shape.Shells)} shell(s), one for the charts glued along their seams")
        if atlas.get("closed"):
            check(len(shape.Solids) == 1 and report.get("solid") is True,
                  f"{name}: {len(shape.Solids)} solid(s), report solid {report.get('solid')} (the atlas is closed)")
        else:
            free = [w for shell in shape.Shells for w in Part.sortEdges(shell.getFreeEdges().Edges)]
            closed = all(Part.Wire(w).isClosed() for w in free)
            check(len(free) == report["free_loops"] and closed,
                  f"{name}: free edges form {len(free)} loop(s), all closed: {closed} (the report: {report['free_loops']})")
        continue
    check(len(shape.Shells) == charts, f"{name}: {len(shape.Shells)} shell(s), one per chart ({charts})")
    if len(shape.Shells) == charts:
        free = [w for shell in shape.Shells for w in Part.sortEdges(shell.getFreeEdges().Edges)]
        closed = all(Part.Wire(w).isClosed() for w in free)
        check(len(free) == loops and closed,
              f"{name}: free edges form {len(free)} loop(s), all closed: {closed} (the domain has {loops})")

sys.exit(1 if failures else 0)
