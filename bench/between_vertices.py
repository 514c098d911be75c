#!/usr/bin/python3
"""How far a fit of a coarse mesh lies from the surface between the mesh's vertices.

  PYTHONPATH=build/python bench/between_vertices.py MESH.off FIT.tbs [MIN_POINTS] [--sphere R]

Flattens MESH as `tbs fit` does with --min-points MIN_POINTS (default 5000), evaluates FIT at
every point's (u, v) and prints, relative to the largest side of the mesh's bounding box, the
largest distance at the vertices and the largest, 99th-percentile and mean distance at the
points the subdivision adds (the guides: edge midpoints of PN triangles). FIT must come from
the same mesh with the vertex parameterization (a `tbs fit` of MESH, subdivided or not).
--sphere R also measures the tessellated spline's distance from the sphere of radius R about
the origin (sphere966.off: 10). docs/benchmarks.md#fairness-between-the-points.
"""
import argparse

import numpy as np
import tbs

ap = argparse.ArgumentParser()
ap.add_argument("mesh")
ap.add_argument("fit")
ap.add_argument("min_points", nargs="?", type=int, default=5000)
ap.add_argument("--sphere", type=float)
a = ap.parse_args()
scan = tbs.read_scan(a.mesh)
p = tbs.parameterize(scan["points"], scan["faces"], scan["normals"], min_points=a.min_points)
if p["guide"] is None:
    raise SystemExit("the mesh was not subdivided: give a MIN_POINTS above its vertex count")
points, uv, guide = np.asarray(p["points"]), np.asarray(p["uv"]), np.asarray(p["guide"])
spline = tbs.load(a.fit)
scale = np.ptp(np.asarray(scan["points"]), axis=0).max()
d = np.linalg.norm(np.asarray(spline.evaluate(uv)) - points, axis=1) / scale
print("%s: vertices max %.2e; guides (%d) max %.2e, 99th percentile %.2e, mean %.2e"
      % (a.fit, d[~guide].max(), guide.sum(), d[guide].max(), np.percentile(d[guide], 99), d[guide].mean()))
if a.sphere:
    x = np.asarray(spline.tessellate(1e-4)["positions"])
    r = np.abs(np.linalg.norm(x, axis=1) - a.sphere) / scale
    print("  distance from the sphere of radius %g: max %.2e, 99th percentile %.2e, mean %.2e (%d samples)"
          % (a.sphere, r.max(), np.percentile(r, 99), r.mean(), len(r)))
