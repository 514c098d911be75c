"""Python.InsideFreeCad: the `tbs` module inside FreeCAD (run by freecadcmd; PYTHONPATH holds
the module, TBS_SOURCE_DIR and TBS_TEST_DIR say where the sample is and where to write).

Fits samples/bracket.ply, exports STEP and loads it as a Part shape: it must be valid, one
shell with the written number of faces, and its bounding box must match the scan's.
"""
import os
import sys
import traceback


def main():
    import FreeCAD  # noqa: F401  (we are inside FreeCAD)
    import Part

    import tbs

    source, work = os.environ["TBS_SOURCE_DIR"], os.environ["TBS_TEST_DIR"]
    os.makedirs(work, exist_ok=True)
    print("FreeCAD %s, tbs %s" % (".".join(FreeCAD.Version()[:3]), tbs.__version__))
    scan = tbs.read_scan(os.path.join(source, "samples", "bracket.ply"))
    spline = tbs.fit(scan["points"], scan["uv"], faces=scan["faces"])
    print("fit:", {k: spline.report[k] for k in ("domain_triangles", "control_points", "max_error", "converged")})
    step = os.path.join(work, "bracket.step")
    written = spline.export(step, cad_tolerance=1e-4, units="mm")
    print("export:", written)
    shape = Part.read(step)
    ok = True
    if not shape.isValid():
        print("FAIL: FreeCAD says the shape is not valid")
        ok = False
    if len(shape.Shells) != 1 or len(shape.Faces) != written["faces"]:
        print("FAIL: %d shells and %d faces, expected 1 and %d" % (len(shape.Shells), len(shape.Faces), written["faces"]))
        ok = False
    pts = scan["points"]
    box = shape.BoundBox
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    gap = max(abs(box.XMin - lo[0]), abs(box.YMin - lo[1]), abs(box.ZMin - lo[2]),
              abs(box.XMax - hi[0]), abs(box.YMax - hi[1]), abs(box.ZMax - hi[2]))
    size = float((hi - lo).max())
    print("bounding box differs from the scan's by %.3g mm (size %.1f mm)" % (gap, size))
    if gap > 0.01 * size:
        print("FAIL: the shape's bounding box is not the scan's")
        ok = False
    return ok


try:
    result = main()
except Exception:  # noqa: BLE001
    traceback.print_exc()
    result = False
sys.stdout.flush()
# freecadcmd's own exit status does not reflect a script's failure: exit explicitly.
os._exit(0 if result else 1)
