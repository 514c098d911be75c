#!/usr/bin/env python3
"""Our STEP and IGES files read back by FreeCAD (Debian's freecad-python3): a valid shape, one
shell, the face count tbs reported, and surface points from tbs's own evaluation within the
CAD tolerance of the read-back shape. Region faces (the default), triangle patches and
--exact, each with its shell built directly (shared edges, no sewing).

usage: freecad_roundtrip.py TBS_EXE SOURCE_DIR WORK_DIR
"""
import json
import os
import random
import re
import subprocess
import sys

for lib in ("/usr/lib/freecad-python3/lib", "/usr/lib/freecad/lib"):
    if os.path.isdir(lib):
        sys.path.append(lib)
import FreeCAD  # noqa: E402
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
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


# Small fits of the bundled scan (a folded sheet with a hole), quick to convert: cubic for the
# compact patches, quadratic for the exact pieces (fewer of them).
def small_fit(degree):
    path = os.path.join(work, f"bracket-d{degree}.tbs")
    run("fit", os.path.join(source, "samples", "bracket.ply"), "-o", path, "--degree", str(degree),
        "--triangles", "60", "--max-iterations", "0", "--units", "mm", "--quiet")
    return path


# Surface points from our own evaluation: random points in random domain triangles.
def surface_points(spline):
    with open(spline) as f:
        doc = json.load(f)
    verts = doc["domain"]["vertices"]
    tris = doc["domain"]["triangles"]
    rng = random.Random(5)
    uv = []
    for _ in range(40):
        a, b, c = (verts[i] for i in rng.choice(tris))
        r1, r2 = rng.random(), rng.random()
        if r1 + r2 > 1:
            r1, r2 = 1 - r1, 1 - r2
        uv.append((a[0] + r1 * (b[0] - a[0]) + r2 * (c[0] - a[0]), a[1] + r1 * (b[1] - a[1]) + r2 * (c[1] - a[1])))
    uv_file = spline + ".uv"
    with open(uv_file, "w") as f:
        f.writelines(f"{u:.17g} {v:.17g}\n" for u, v in uv)
    return [tuple(map(float, line.split())) for line in run("eval", spline, "--input", uv_file).splitlines()]


for mode, degree in (("regions", 3), ("triangles", 3), ("exact", 2)):
    spline = small_fit(degree)
    points = surface_points(spline)
    for ext in ("step", "igs"):
        out = os.path.join(work, f"bracket-{mode}.{ext}")
        args = ["convert", spline, out, "--quiet"]
        args += {"regions": [], "triangles": ["--faces", "triangles", "--cad-tolerance", "1e-4"],
                 "exact": ["--exact"]}[mode]
        summary = run(*args)
        faces = int(re.search(r"shape +(\d+) B-spline faces", summary).group(1))
        m = re.search(r"max deviation +([0-9.eE+-]+) mm \(tolerance ([0-9.eE+-]+)\)", summary)
        # Exact pieces are exact up to roundoff, but the exact form has sliver pieces (cells of
        # the knot-line arrangement), where the distance solver itself is off by up to about
        # 5e-7 of the model size: they are held to the default CAD tolerance, 1e-6 of it.
        tol = float(m.group(2)) if m else 1e-6 * 157
        shape = Part.Shape()
        shape.read(out)
        name = f"{mode} {ext.upper()} ({faces} faces)"
        check(shape.isValid(), f"{name}: FreeCAD finds the shape valid")
        check(len(shape.Shells) == 1, f"{name}: one shell (found {len(shape.Shells)})")
        check(len(shape.Faces) == faces, f"{name}: {faces} faces written, {len(shape.Faces)} read")
        worst = max(shape.distToShape(Part.Vertex(FreeCAD.Vector(*p)))[0] for p in points)
        check(worst <= tol, f"{name}: surface points within {tol:.3g} mm of the shape (worst {worst:.3g})")

if failures:
    sys.exit(f"{len(failures)} check(s) failed")
print(f"FreeCAD {'.'.join(FreeCAD.Version()[:3])}: all checks passed")
