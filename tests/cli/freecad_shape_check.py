#!/usr/bin/env python3
"""FreeCAD (Debian's freecad-python3) reads a STEP or IGES file that `tbs convert` wrote and
finds what its report says: a valid shape, one shell, the reported number of faces, and free
edges forming one closed loop per boundary loop of the spline's domain (the outer boundary and
each hole).

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
loops = len(json.load(open(spline))["domain"]["boundary_loops"])
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
    check(len(shape.Shells) == 1, f"{name}: one shell (found {len(shape.Shells)})")
    check(len(shape.Faces) == report["faces"], f"{name}: {len(shape.Faces)} faces read, {report['faces']} written")
    if len(shape.Shells) == 1:
        free = Part.sortEdges(shape.Shells[0].getFreeEdges().Edges)
        closed = all(Part.Wire(w).isClosed() for w in free)
        check(len(free) == loops and closed,
              f"{name}: free edges form {len(free)} loop(s), all closed: {closed} (the domain has {loops})")

sys.exit(1 if failures else 0)
