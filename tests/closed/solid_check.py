#!/usr/bin/python3
"""The judge of tbs's CAD solids of closed parts: `tbs convert FIT.tbs PART.step` at the
defaults, read back and worked on in FreeCAD, against the exact part (parts.py's NAME.brep).

    /usr/bin/python3 tests/closed/solid_check.py TBS_EXE FIT.tbs EXACT.brep OUT.step \
        [--volume 5e-3] [--slices 20] [--max-faces N] [--max-mb 2] [--report OUT.json]

Asserts (each failure is named; exit 1 if any):
  convert   exit 0; the summary and the report say solid, with a volume
  solid     FreeCAD reads one valid Solid (one closed shell)
  volume    |V - V_exact| <= --volume x V_exact (FreeCAD's volume of the read-back solid)
  slice     at --slices evenly spaced planes across the exact part's box along each axis:
            wherever the exact part has a section, the solid's section is closed wires
  drill     the solid minus a cylinder through its middle (along z, radius 1/10 of the smaller
            of x and y extents) is a valid shape, and the volume drops by the exact part's drop
            within 1 %
  common    the solid and a box across its middle (1/5 of the z extent): a valid shape whose
            volume is within 1 % of the exact part's
  faces     at most --max-faces faces (default: no bound), the file at most --max-mb MB
            (default: no bound)
  iges      `tbs convert FIT.tbs OUT.igs`: FreeCAD reads one valid closed shell or solid whose
            volume is within --volume of the exact part's
Prints one JSON object with every number (also to --report).
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.append("/usr/lib/freecad/lib")
import FreeCAD  # noqa: E402  (before Part)
import Part  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("tbs")
    ap.add_argument("fit")
    ap.add_argument("exact")
    ap.add_argument("step")
    ap.add_argument("--volume", type=float, default=5e-3)
    ap.add_argument("--slices", type=int, default=20)
    ap.add_argument("--max-faces", type=int, default=0)
    ap.add_argument("--max-mb", type=float, default=0)
    ap.add_argument("--convert-args", default="")
    ap.add_argument("--report")
    a = ap.parse_args()
    out = {"reasons": []}
    reasons = out["reasons"]
    report_file = a.step + ".json"
    cmd = [a.tbs, "convert", a.fit, a.step, "--report", report_file, "--quiet", *a.convert_args.split()]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1200)
    out["convert_seconds"] = time.time() - t0
    out["convert_exit"] = p.returncode
    if p.returncode != 0:
        reasons.append(f"tbs convert exit {p.returncode}: {p.stderr.strip()[-300:]}")
        return finish(a, out)
    rep = json.load(open(report_file))
    out["report"] = {k: rep.get(k) for k in ("faces", "shells", "free_edges", "solid", "volume", "file_bytes",
                                             "max_position_deviation", "within_tolerance", "regions")}
    if rep.get("solid") is not True or "volume" not in rep:
        reasons.append(f"the report says solid {rep.get('solid')}, volume {rep.get('volume')}")
    if "solid " not in p.stdout:
        reasons.append("the summary has no solid line")

    exact = Part.Shape()
    exact.read(a.exact)
    s = Part.Shape()
    t0 = time.time()
    s.read(a.step)
    out["read_seconds"] = time.time() - t0
    out["faces"], out["exact_faces"] = len(s.Faces), len(exact.Faces)
    out["file_mb"] = os.path.getsize(a.step) / 1e6
    if a.max_faces and len(s.Faces) > a.max_faces:
        reasons.append(f"{len(s.Faces)} faces > {a.max_faces}")
    if a.max_mb and out["file_mb"] > a.max_mb:
        reasons.append(f"{out['file_mb']:.2f} MB > {a.max_mb}")
    out["valid"] = s.isValid()
    out["solids"] = len(s.Solids)
    if not out["valid"] or len(s.Solids) != 1:
        reasons.append(f"FreeCAD reads {len(s.Solids)} solids, valid {out['valid']}")
        return finish(a, out)
    solid = s.Solids[0]
    out["volume"], out["exact_volume"] = solid.Volume, exact.Volume
    out["volume_error"] = (solid.Volume - exact.Volume) / exact.Volume
    out["tbs_volume_error"] = (rep.get("volume", 0) - exact.Volume) / exact.Volume
    if abs(out["volume_error"]) > a.volume:
        reasons.append(f"volume {solid.Volume:.6g} is {out['volume_error']:+.2%} off the exact {exact.Volume:.6g}")
    if abs(out["tbs_volume_error"]) > a.volume:
        reasons.append(f"the report's volume {rep.get('volume')} is {out['tbs_volume_error']:+.2%} off")

    bb = exact.BoundBox
    slices = {}
    for axis in "xyz":
        lo, hi = getattr(bb, axis.upper() + "Min"), getattr(bb, axis.upper() + "Max")
        d = FreeCAD.Vector(*(1 if c == axis else 0 for c in "xyz"))
        bad, seconds = [], 0.0
        for i in range(1, a.slices + 1):
            c = lo + (hi - lo) * i / (a.slices + 1)
            if not exact.slice(d, c):
                continue
            t0 = time.time()
            w = solid.slice(d, c)
            seconds += time.time() - t0
            if not w or not all(x.isClosed() for x in w):
                bad.append(round(c, 4))
        slices[axis] = {"bad": bad, "mean_seconds": seconds / a.slices}
        if bad:
            reasons.append(f"slices across {axis} at {bad} are not closed wires")
    out["slices"] = slices

    c = bb.Center
    r = 0.1 * min(bb.XLength, bb.YLength)
    cyl = Part.makeCylinder(r, 3 * bb.ZLength, FreeCAD.Vector(c.x, c.y, bb.ZMin - bb.ZLength), FreeCAD.Vector(0, 0, 1))
    t0 = time.time()
    cut = solid.cut(cyl)
    out["drill_seconds"] = time.time() - t0
    drop, exact_drop = solid.Volume - cut.Volume, exact.Volume - exact.cut(cyl).Volume
    out["drill"] = {"valid": cut.isValid(), "drop": drop, "exact_drop": exact_drop}
    if not cut.isValid() or abs(drop - exact_drop) > 0.01 * max(exact_drop, 1e-12):
        reasons.append(f"drill: valid {cut.isValid()}, volume drop {drop:.6g} against {exact_drop:.6g}")
    box = Part.makeBox(2 * bb.XLength, 2 * bb.YLength, 0.2 * bb.ZLength,
                       FreeCAD.Vector(bb.XMin - bb.XLength / 2, bb.YMin - bb.YLength / 2, c.z - 0.1 * bb.ZLength))
    com, exact_com = solid.common(box), exact.common(box)
    out["common"] = {"valid": com.isValid(), "volume": com.Volume, "exact_volume": exact_com.Volume}
    if not com.isValid() or abs(com.Volume - exact_com.Volume) > 0.01 * exact_com.Volume:
        reasons.append(f"common: valid {com.isValid()}, volume {com.Volume:.6g} against {exact_com.Volume:.6g}")

    # The IGES of the same fit: FreeCAD reads one valid solid (or closed shell) of that volume.
    iges = os.path.splitext(a.step)[0] + ".igs"
    p = subprocess.run([a.tbs, "convert", a.fit, iges, "--quiet", *a.convert_args.split()], capture_output=True,
                       text=True, timeout=1200)
    if p.returncode != 0:
        reasons.append(f"tbs convert to IGES exit {p.returncode}: {p.stderr.strip()[-300:]}")
        return finish(a, out)
    g = Part.Shape()
    g.read(iges)
    closed = [sh.isClosed() for sh in g.Shells]
    out["iges"] = {"valid": g.isValid(), "solids": len(g.Solids), "shells": len(g.Shells), "closed": closed}
    if not g.isValid() or len(g.Shells) != 1 or not all(closed):
        reasons.append(f"IGES: FreeCAD reads valid {g.isValid()}, {len(g.Solids)} solids, shells closed {closed}")
    else:
        v = g.Volume if g.Solids else Part.Solid(g.Shells[0]).Volume
        out["iges"]["volume_error"] = (v - exact.Volume) / exact.Volume
        if abs(out["iges"]["volume_error"]) > a.volume:
            reasons.append(f"IGES volume {v:.6g} is {out['iges']['volume_error']:+.2%} off")
    return finish(a, out)


def finish(a, out):
    text = json.dumps(out, indent=1, default=float)
    print(text)
    if a.report:
        with open(a.report, "w") as f:
            f.write(text)
    for r in out["reasons"]:
        print("FAIL: " + r)
    return 1 if out["reasons"] else 0


if __name__ == "__main__":
    sys.exit(main())
