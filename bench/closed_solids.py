#!/usr/bin/python3
"""CAD export of closed parts: what `tbs convert FIT.tbs PART.step` (the defaults, or --args)
makes of the fits of tests/closed/closed_check.py, and how FreeCAD works with it.

    /usr/bin/python3 tests/closed/closed_check.py build/cli/tbs build/python WORK   # the fits
    /usr/bin/python3 bench/closed_solids.py build/cli/tbs WORK [--args "--cad-tolerance 2.5e-4"]

For every WORK/fits/NAME-KIND.tbs (NAME a part of tests/closed/parts.py, KIND mesh or cloud):
charts and seams (tbs info), faces, poles, solid or shell, the largest face deviation against
the CAD tolerance, file size, seconds per stage and peak memory of the convert (wait4's
ru_maxrss), FreeCAD's volume against the exact part's, and FreeCAD's seconds for one slice
(mean of 3 planes across the middle, one per axis) and one distToShape query (mean of 3
points off the part). Fits whose report (NAME-KIND.json) says they did not converge are
listed, not converted. Prints a Markdown table.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.append("/usr/lib/freecad/lib")
import FreeCAD  # noqa: E402  (before Part)
import Part  # noqa: E402


def run_measured(cmd):
    with tempfile.TemporaryFile() as err:
        t0 = time.time()
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        return p.returncode, err.read().decode(errors="replace"), usage.ru_maxrss * 1024, time.time() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("tbs")
    ap.add_argument("work")
    ap.add_argument("--args", default="", help="extra arguments for tbs convert")
    a = ap.parse_args()
    rows = []
    fits = sorted(f for f in os.listdir(os.path.join(a.work, "fits")) if f.endswith(".tbs"))
    for f in fits:
        name, kind = f[:-4].rsplit("-", 1)
        fit = os.path.join(a.work, "fits", f)
        try:
            converged = json.load(open(fit[:-4] + ".json")).get("converged")
        except OSError:
            converged = None
        if converged is False:
            rows.append({"part": name, "input": kind, "charts": "-", "seams": "-", "error": "the fit did not converge"})
            continue
        step = os.path.join(a.work, "fits", f[:-4] + "-bench.step")
        rep = step + ".json"
        info = json.loads(subprocess.run([a.tbs, "info", fit], capture_output=True, text=True).stdout)
        rc, err, peak, seconds = run_measured([a.tbs, "convert", fit, step, "--report", rep, "--quiet", *a.args.split()])
        row = {"part": name, "input": kind, "charts": info["atlas"]["charts"], "seams": info["atlas"]["seams"]}
        if rc != 0:
            row["error"] = "convert failed: " + err.strip()[-200:]
            rows.append(row)
            continue
        r = json.load(open(rep))
        exact = Part.Shape()
        exact.read(os.path.join(a.work, name + ".brep"))
        s = Part.Shape()
        s.read(step)
        bb = exact.BoundBox
        t0 = time.time()
        for axis, c in (("x", bb.Center.x), ("y", bb.Center.y), ("z", bb.Center.z)):
            s.slice(FreeCAD.Vector(*(1 if q == axis else 0 for q in "xyz")), c + 1e-3 * bb.DiagonalLength)
        slice_s = (time.time() - t0) / 3
        t0 = time.time()
        for k in range(3):
            p = bb.Center + FreeCAD.Vector(bb.XLength * (0.7 + 0.1 * k), bb.YLength * 0.3, bb.ZLength * 0.2)
            s.distToShape(Part.Vertex(p))
        dist_s = (time.time() - t0) / 3
        row.update(faces=r["faces"], poles=r["regions"]["poles"] if "regions" in r else None,
                   form="solid" if r.get("solid") else f"{r['shells']} shell(s)",
                   valid=s.isValid(), dev=r.get("max_position_deviation"), tol=r.get("cad_tolerance"),
                   mb=r["file_bytes"] / 1e6, seconds=seconds, stages=r["stage_seconds"], peak_gb=peak / 1e9,
                   volume_error=(s.Volume - exact.Volume) / exact.Volume if s.Solids else None,
                   slice_s=slice_s, dist_s=dist_s)
        rows.append(row)
        print(json.dumps(row, default=float), file=sys.stderr, flush=True)
    print("| part | input | charts | seams | faces | poles | shape | FreeCAD valid | max dev / CAD tol | MB | "
          "convert s (regions / shell + check / write) | peak GB | volume err | slice s | distToShape s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['part']} | {r['input']} | {r['charts']} | {r['seams']} | not measured: {r['error']} |")
            continue
        st = r["stages"]
        ve = f"{100 * r['volume_error']:+.2f} %" if r["volume_error"] is not None else "-"
        print(f"| {r['part']} | {r['input']} | {r['charts']} | {r['seams']} | {r['faces']} | {r['poles']} | {r['form']} | "
              f"{'yes' if r['valid'] else 'no'} | {r['dev']:.3g} / {r['tol']:.3g} | {r['mb']:.2f} | "
              f"{r['seconds']:.1f} ({st.get('regions', 0):.1f} / {st.get('shell', 0) + st.get('check', 0):.1f} / "
              f"{st.get('translate', 0) + st.get('write', 0):.1f}) | {r['peak_gb']:.2f} | {ve} | {r['slice_s']:.2f} | {r['dist_s']:.2f} |")


if __name__ == "__main__":
    main()
