#!/usr/bin/python3
"""FreeCAD's ReverseEngineering.approxSurface as a peer in bench/run.py.

  /usr/bin/python3 bench/freecad_approx.py POINTS.xyz OUT.brep POLES [DEGREE]

Fits ONE tensor-product B-spline surface of degree DEGREE (default 3) in u and v with POLES x
POLES control points to the points (text, x y z per line; `tbs_peers points` writes it), with
FreeCAD 0.20's defaults otherwise (smoothing on, weight 0.1, 5 parameter-correction
iterations), and writes it as a BRep face. Prints one JSON object: the poles, the degrees and
the seconds approxSurface took (reading and writing not included).

Needs Debian's freecad-python3 (FreeCAD's modules in /usr/lib/freecad/lib).
"""
import json
import os
import sys
import time

sys.path.append("/usr/lib/freecad/lib")
import FreeCAD  # noqa: E402,F401  (initialises FreeCAD before its modules)
import Part  # noqa: E402
import ReverseEngineering  # noqa: E402


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    points_path, out, poles = sys.argv[1], sys.argv[2], int(sys.argv[3])
    degree = int(sys.argv[4]) if len(sys.argv) > 4 else 3
    points = []
    with open(points_path) as f:
        for line in f:
            x, y, z = line.split()
            points.append((float(x), float(y), float(z)))
    start = time.perf_counter()
    surface = ReverseEngineering.approxSurface(
        Points=points, UDegree=degree, VDegree=degree, NbUPoles=poles, NbVPoles=poles)
    seconds = time.perf_counter() - start
    tmp = out + ".tmp"
    Part.Face(surface).exportBrep(tmp)
    os.replace(tmp, out)
    print(json.dumps({"poles_u": surface.NbUPoles, "poles_v": surface.NbVPoles,
                      "degree_u": surface.UDegree, "degree_v": surface.VDegree,
                      "seconds": round(seconds, 3)}))


if __name__ == "__main__":
    main()
