#!/usr/bin/env python3
"""FreeCAD works with tbs's default CAD output, as a CAD user would: the bundled bracket scan
is fitted with default options and converted with `tbs convert bracket.tbs bracket.step`
(region faces). FreeCAD (Debian's freecad-python3) must then

- read the STEP (and the IGES) as one valid shell of at most 20 faces, the STEP at most 2 MB;
- find the free edges forming exactly the outer loop plus one loop per hole;
- find 10,000 points of the spline (tbs eval) within the CAD tolerance of the shape;
- trim it with a box across the middle: common and cut valid, their areas adding up to the
  part's within 0.1 %;
- cut it with three planes across the part into connected wires as long as the spline's
  own section;
- thicken it (makeOffsetShape with the intersection join, T = 1 % of the part's size) into a
  valid solid whose volume is within 2 % of area x T.

A creased and holed synthetic sheet: one region face per flank, the crease one edge shared by
both, the face normals at the crease within 0.5 degrees of the spline's on each side.

The same STEP and IGES bytes (but the time stamp) for 1 and 2 threads.

usage: freecad_cad_check.py TBS_EXE SOURCE_DIR WORK_DIR
"""
import json
import math
import multiprocessing
import os
import random
import re
import subprocess
import sys
import time

for lib in ("/usr/lib/freecad-python3/lib", "/usr/lib/freecad/lib"):
    if os.path.isdir(lib):
        sys.path.append(lib)
import FreeCAD  # noqa: E402  (FreeCAD before Part: Part alone crashes in the offset)
import Part  # noqa: E402

tbs, source, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
failures = []


def run(*args):
    r = subprocess.run([tbs, *args], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"tbs {' '.join(args)} failed ({r.returncode}): {r.stderr}")
    return r.stdout


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)


def domain_points(spline, count, seed):
    """Random parameter points in random domain triangles (area-weighted)."""
    with open(spline) as f:
        doc = json.load(f)
    verts = doc["domain"]["vertices"]
    tris = doc["domain"]["triangles"]
    areas = []
    for t in tris:
        a, b, c = (verts[i] for i in t)
        areas.append(abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2)
    rng = random.Random(seed)
    uv = []
    for t in rng.choices(tris, weights=areas, k=count):
        a, b, c = (verts[i] for i in t)
        r1, r2 = rng.random(), rng.random()
        if r1 + r2 > 1:
            r1, r2 = 1 - r1, 1 - r2
        uv.append((a[0] + r1 * (b[0] - a[0]) + r2 * (c[0] - a[0]), a[1] + r1 * (b[1] - a[1]) + r2 * (c[1] - a[1])))
    return uv, doc


def evaluate(spline, uv, normals=False):
    path = spline + ".uv"
    with open(path, "w") as f:
        f.writelines(f"{u:.17g} {v:.17g}\n" for u, v in uv)
    out = run("eval", spline, "--input", path, *(["--normals"] if normals else []))
    return [tuple(map(float, line.split())) for line in out.splitlines()]


def without_time_stamp(path):
    """The file's bytes without the writing time: STEP's FILE_NAME, IGES's global section."""
    text = open(path, "rb").read().decode("latin-1")
    if path.endswith(".step"):
        return re.sub(r"FILE_NAME\('[^']*','[^']*'", "FILE_NAME(", text)
    return "".join(line for line in text.splitlines(True) if len(line) < 73 or line[72] != "G")


_worker_shape = None


def load_worker_shape(path):
    global _worker_shape
    _worker_shape = shape_of(path)


def worker_distance(p):
    return _worker_shape.distToShape(Part.Vertex(FreeCAD.Vector(*p)))[0]


def shape_of(path):
    shape = Part.Shape()
    shape.read(path)
    return shape


# --- The bracket, as scripts/demo.sh makes it --------------------------------------------------
spline = os.path.join(work, "bracket.tbs")
run("fit", os.path.join(source, "samples", "bracket.ply"), "-o", spline, "--units", "mm", "--quiet")
step = os.path.join(work, "bracket.step")
report_path = os.path.join(work, "bracket.report.json")
t0 = time.time()
run("convert", spline, step, "--report", report_path, "--quiet")
print(f"tbs convert: {time.time() - t0:.2f} s")
report = json.load(open(report_path))
tol = report["cad_tolerance"]
size = os.path.getsize(step)
check(report["faces"] <= 20, f"bracket: {report['faces']} faces (at most 20)")
check(size <= 2e6, f"bracket: STEP of {size / 1e6:.2f} MB (at most 2 MB)")

shape = shape_of(step)
check(shape.isValid(), "bracket STEP: FreeCAD finds the shape valid")
check(len(shape.Shells) == 1, f"bracket STEP: one shell (found {len(shape.Shells)})")
check(len(shape.Faces) == report["faces"], f"bracket STEP: {report['faces']} faces written, {len(shape.Faces)} read")
uv, doc = domain_points(spline, 10000, 7)
loops = len(doc["domain"]["boundary_loops"])
free = Part.sortEdges(shape.Shells[0].getFreeEdges().Edges)
closed = [Part.Wire(w).isClosed() for w in free]
check(len(free) == loops and all(closed),
      f"bracket STEP: free edges form {len(free)} loops, closed: {closed} (the outer loop and {loops - 1} hole)")

t0 = time.time()
points = evaluate(spline, uv)
# distToShape takes about 27 ms a point here (OCCT sets up a projection per call): the points
# are shared out to a process per core.
with multiprocessing.Pool(os.cpu_count() or 1, initializer=load_worker_shape, initargs=(step,)) as pool:
    worst = max(pool.map(worker_distance, points, chunksize=250))
check(worst <= tol, f"bracket STEP: 10,000 spline points within {worst:.3g} mm of the shape (CAD tolerance {tol:.3g} mm)"
      f" [{time.time() - t0:.1f} s]")

# Trimmed by a box across the middle.
bb = shape.BoundBox
box = Part.makeBox(bb.XLength * 0.5, bb.YLength * 1.2, bb.ZLength * 1.4 + 2,
                   FreeCAD.Vector(bb.XMin + bb.XLength * 0.25, bb.YMin - 0.1 * bb.YLength, bb.ZMin - 0.2 * bb.ZLength - 1))
common, cut = shape.common(box), shape.cut(box)
check(common.isValid() and cut.isValid() and len(common.Faces) > 0 and len(cut.Faces) > 0,
      f"bracket: common and cut with a box are valid ({len(common.Faces)} and {len(cut.Faces)} faces)")
ratio = (common.Area + cut.Area) / shape.Area
check(abs(ratio - 1) <= 1e-3, f"bracket: areas of common + cut = {ratio:.6f} x the part's (within 0.1 %)")

# Plane sections across the part (constant y; the bracket's y is 90 v): connected wires as long
# as the spline's section, where the plane misses the hole.
for frac in (0.2, 0.35, 0.85):
    y = bb.YMin + frac * bb.YLength
    wires = shape.slice(FreeCAD.Vector(0, 1, 0), y)
    v = y / 90.0
    us = [i / 2000 for i in range(2001)]
    line = [p for p in evaluate(spline, [(u, v) for u in us])]
    length = sum(math.dist(line[i], line[i + 1]) for i in range(len(line) - 1))
    got = sum(w.Length for w in wires)
    check(len(wires) == 1 and abs(got - length) <= 0.01 * length,
          f"bracket: section at y = {y:.1f} mm is {len(wires)} connected wire(s) of length {got:.2f} mm "
          f"(spline: {length:.2f} mm)")

# Thickened into a solid.
T = 0.01 * bb.DiagonalLength
t0 = time.time()
solid = shape.Shells[0].makeOffsetShape(T, 1e-3, join=2, fill=True)
ratio = abs(solid.Volume) / (shape.Area * T)
check(solid.ShapeType == "Solid" and solid.isValid() and abs(ratio - 1) <= 0.02,
      f"bracket: thickened by {T:.2f} mm into a valid {solid.ShapeType}, volume {ratio:.4f} x area x T "
      f"[{time.time() - t0:.1f} s]")

iges = os.path.join(work, "bracket.igs")
run("convert", spline, iges, "--quiet")
shape = shape_of(iges)
check(shape.isValid() and len(shape.Shells) == 1 and len(shape.Faces) == report["faces"],
      f"bracket IGES: valid, {len(shape.Shells)} shell, {len(shape.Faces)} faces")

# Same bytes for 1 and 2 threads.
for ext in ("step", "igs"):
    one, two = (os.path.join(work, f"threads{n}.{ext}") for n in (1, 2))
    run("convert", spline, one, "--threads", "1", "--product-name", "bracket", "--quiet")
    run("convert", spline, two, "--threads", "2", "--product-name", "bracket", "--quiet")
    check(without_time_stamp(one) == without_time_stamp(two), f"bracket {ext.upper()}: the same bytes for 1 and 2 threads")

# --- A creased and holed synthetic sheet --------------------------------------------------------
# z(u, v) = 0.1 sin(5u) cos(4v) folded by 60 degrees along u = 0.5, a round hole in each flank;
# a triangle mesh (so that the fit finds the crease from the dihedral angles).
n = 60
crease = n // 2
rows = []
for j in range(n + 1):
    for i in range(n + 1):
        u, v = i / n, j / n
        z = 0.1 * math.sin(5 * u) * math.cos(4 * v) - math.tan(math.radians(30)) * abs(u - 0.5)
        rows.append((u, v, z))
holes = [((0.25, 0.5), 0.1), ((0.75, 0.4), 0.12)]
inside = [any(math.hypot(u - c[0], v - c[1]) < r for c, r in holes) for u, v, _ in rows]
faces = []
for j in range(n):
    for i in range(n):
        a, b, c, d = j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i
        for tri in ((a, b, c), (a, c, d)):
            if not any(inside[k] for k in tri):
                faces.append(tri)
sheet = os.path.join(work, "sheet.ply")
with open(sheet, "w") as f:
    f.write("ply\nformat ascii 1.0\n")
    f.write(f"element vertex {len(rows)}\nproperty double x\nproperty double y\nproperty double z\n")
    f.write("property double u\nproperty double v\n")
    f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    f.writelines(f"{u!r} {v!r} {z!r} {u!r} {v!r}\n" for u, v, z in rows)
    f.writelines(f"3 {a} {b} {c}\n" for a, b, c in faces)
sheet_tbs = os.path.join(work, "sheet.tbs")
run("fit", sheet, "-o", sheet_tbs, "--quiet")
sheet_step = os.path.join(work, "sheet.step")
sheet_report = os.path.join(work, "sheet.report.json")
run("convert", sheet_tbs, sheet_step, "--report", sheet_report, "--quiet")
sr = json.load(open(sheet_report))
shape = shape_of(sheet_step)
check(shape.isValid() and len(shape.Shells) == 1, "sheet STEP: valid, one shell")
check(len(shape.Faces) == 2, f"sheet: a region face on each flank ({len(shape.Faces)} faces)")
shared = [e for e in shape.Edges if len(shape.ancestorsOfType(e, Part.Face)) == 2]
check(len(shared) == 1, f"sheet: the crease is one edge shared by both faces ({len(shared)} shared edges)")
sheet_doc = json.load(open(sheet_tbs))
loops = len(sheet_doc["domain"]["boundary_loops"])
free = Part.sortEdges(shape.Shells[0].getFreeEdges().Edges)
check(len(free) == loops == 3, f"sheet: free edges form {len(free)} loops (the outer loop and 2 holes)")
# Normals on each side of the crease: the spline's (tbs eval) against the face's there.
worst = 0
for k in range(1, 20):
    v = k / 20
    for side in (-1, 1):
        u = 0.5 + side * 1e-7
        x, y, z, nx, ny, nz = evaluate(sheet_tbs, [(u, v)], normals=True)[0]
        face = min(shape.Faces, key=lambda f: f.distToShape(Part.Vertex(FreeCAD.Vector(x, y, z)))[0]
                   + (0 if (f.CenterOfMass.x - 0.5) * side > 0 else 1))
        fu, fv = face.Surface.parameter(FreeCAD.Vector(x, y, z))
        n = face.Surface.normal(fu, fv)
        dot = max(-1.0, min(1.0, n.x * nx + n.y * ny + n.z * nz))
        worst = max(worst, math.degrees(math.acos(dot)))
check(worst <= 0.5, f"sheet: face normals at the crease within {worst:.3f} degrees of the spline's (0.5)")

if failures:
    sys.exit(f"{len(failures)} check(s) failed")
print(f"FreeCAD {'.'.join(FreeCAD.Version()[:3])}: all checks passed")
