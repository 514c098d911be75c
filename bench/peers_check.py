#!/usr/bin/env python3
"""Checks the side-by-side tools of bench/run.py on a case with a known answer.

  python3 bench/peers_check.py TBS TBS_PEERS WORKDIR

Points on the plane z = 0.3 x + 0.2 y (with parameters u = x, v = y) are fitted three ways:
`tbs fit`, OpenCASCADE's plate (`tbs_peers plate`) and FreeCAD's approxSurface
(bench/freecad_approx.py). A second point set lies 0.01 above the plane along z; its distance
(over the middle of the plane) to each surface, measured by `tbs_peers distance`, must be
0.01 / sqrt(1 + 0.3^2 + 0.2^2) for every point, whichever program made the surface. Exit status 0 when all agree within 1e-6.
"""
import json
import math
import os
import struct
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    tbs, peers, work = sys.argv[1:4]
    os.makedirs(work, exist_ok=True)
    n = 40
    grid = [(i / (n - 1), j / (n - 1)) for j in range(n) for i in range(n)]
    plane = os.path.join(work, "plane.ply")
    with open(plane, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty double x\n"
                 "property double y\nproperty double z\nproperty double u\nproperty double v\n"
                 "end_header\n" % len(grid)).encode())
        for x, y in grid:
            f.write(struct.pack("<5d", x, y, 0.3 * x + 0.2 * y, x, y))
    plane_xyz = os.path.join(work, "plane.xyz")
    with open(plane_xyz, "w") as f:
        for x, y in grid:
            f.write("%.17g %.17g %.17g\n" % (x, y, 0.3 * x + 0.2 * y))
    # Above the middle of the plane only: near the border the closest surface point can be on
    # the border, further away than the plane.
    above = os.path.join(work, "above.xyz")
    with open(above, "w") as f:
        for x, y in grid:
            x, y = 0.2 + 0.6 * x, 0.2 + 0.6 * y
            f.write("%.17g %.17g %.17g\n" % (x, y, 0.3 * x + 0.2 * y + 0.01))
    # The box of `above` is 0.6 x 0.6 x 0.3: distances are over its largest side, 0.6.
    expected = 0.01 / math.sqrt(1 + 0.3 ** 2 + 0.2 ** 2) / 0.6

    def run(cmd):
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit("peers_check: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()))
        return p.stdout

    surfaces = {}
    run([tbs, "fit", plane, "-o", os.path.join(work, "plane.tbs"), "-q"])
    surfaces["tbs"] = os.path.join(work, "plane.tbs")
    print(run([peers, "plate", plane, os.path.join(work, "plate.brep"), "--constraints", "200"]).strip())
    surfaces["plate"] = os.path.join(work, "plate.brep")
    print(run(["/usr/bin/python3", os.path.join(ROOT, "bench", "freecad_approx.py"), plane_xyz,
               os.path.join(work, "freecad.brep"), "6"]).strip())
    surfaces["freecad"] = os.path.join(work, "freecad.brep")

    failed = []
    for name, surface in surfaces.items():
        d = json.loads(run([peers, "distance", above, surface]))
        ok = all(abs(d[k] - expected) < 1e-6 for k in ("max", "rms", "mean")) and d["points"] == n * n
        print("%-8s max %.9f rms %.9f mean %.9f (expected %.9f) %s" % (
            name, d["max"], d["rms"], d["mean"], expected, "ok" if ok else "WRONG"))
        if not ok:
            failed.append(name)
    if failed:
        sys.exit("peers_check: distances disagree with the known answer for: " + ", ".join(failed))


if __name__ == "__main__":
    main()
