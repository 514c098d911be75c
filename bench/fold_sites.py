#!/usr/bin/python3
"""Where a fit folds: in the data, or in the margin the domain adds beyond it.

  PYTHONPATH=build/python bench/fold_sites.py MESH FIT.tbs

FIT must be a `tbs fit MESH -o FIT.tbs` of a mesh without parameters. The mesh is flattened
again as `tbs fit` did it (subdivided to the fit's point count when the fit used guide points;
the script checks that the count matches), and for every
domain triangle where the fit folds (`tbs info`: shape.folded_triangles) the script prints
its corners on the domain boundary, the mesh points (vertices and subdivision points) inside
it, the share of its area that the flattened mesh covers, and how far the data itself turns
there: the largest angle between the normals of two mesh faces (of the flattened, possibly
subdivided mesh) whose parameter centroids lie in the triangle. A share near 0 is a fold in the
margin: the part of the domain between the outline the domain builder simplifies and offsets
and the data (fit_outline.cpp), where no point holds the surface. Then the totals, and the
share of the whole domain that the mesh leaves uncovered. docs/benchmarks.md#where-the-folds-are.
"""
import argparse
import json
import os
import subprocess

import numpy as np
import tbs

ap = argparse.ArgumentParser()
ap.add_argument("mesh")
ap.add_argument("fit")
ap.add_argument("--samples", type=int, default=400, help="random samples per domain triangle")
a = ap.parse_args()

tbs_cmd = os.environ.get("TBS", os.path.join(os.path.dirname(__file__), "..", "build", "cli", "tbs"))
info = json.loads(subprocess.run([tbs_cmd, "info", a.fit], check=True, capture_output=True, text=True).stdout)
folded = info["shape"]["folded_triangles"]
doc = json.load(open(a.fit))
V = np.asarray(doc["domain"]["vertices"], float)
T = np.asarray(doc["domain"]["triangles"], int)
boundary = {v for loop in doc["domain"].get("boundary_loops", []) for v in loop}
fit_points = doc["metadata"]["fit"]["points"]

scan = tbs.read_scan(a.mesh)
if scan["faces"] is None:
    raise SystemExit("%s has no faces: the script needs a mesh" % a.mesh)
# A fit with guides subdivided the mesh 1-to-4 until it had --min-points points, at least once:
# asking for the fit's own count repeats the same number of subdivisions.
guided = doc["metadata"]["fit"].get("guide_points", 0) > 0
p = tbs.parameterize(scan["points"], scan["faces"], scan["normals"], min_points=fit_points if guided else 0)
uv, faces = np.asarray(p["uv"]), np.asarray(p["faces"])
if len(uv) != fit_points:
    raise SystemExit("the flattening gives %d points, the fit had %d: was FIT fitted from MESH?" % (len(uv), fit_points))


def covered(x):
    """True for each (u, v) in x (K, 2) inside some face of the flattened mesh."""
    lo, hi = x.min(0), x.max(0)
    tri = uv[faces]  # F, 3, 2
    near = (tri.min(1) <= hi).all(1) & (tri.max(1) >= lo).all(1)
    tri = tri[near]
    out = np.zeros(len(x), bool)
    if len(tri) == 0:
        return out
    a0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    for k, q in enumerate(x):
        d = q - a0
        s = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
        t = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
        out[k] = np.any((s >= 0) & (t >= 0) & (s + t <= 1))
    return out


rng = np.random.default_rng(1)


def samples(t, k):
    return rng.dirichlet([1, 1, 1], k) @ V[T[t]]


def in_triangle(t, x):
    a0, e1, e2 = V[T[t][0]], V[T[t][1]] - V[T[t][0]], V[T[t][2]] - V[T[t][0]]
    m = np.linalg.solve(np.array([e1, e2]).T, (x - a0).T).T
    return (m >= 0).all(1) & (m.sum(1) <= 1)


def inside(t):
    return int(in_triangle(t, uv).sum())


xyz = np.asarray(p["points"], float)
face_normal = np.cross(xyz[faces[:, 1]] - xyz[faces[:, 0]], xyz[faces[:, 2]] - xyz[faces[:, 0]])
face_normal /= np.maximum(np.linalg.norm(face_normal, axis=1), 1e-300)[:, None]
face_centroid = uv[faces].mean(1)


def turn(t):
    """The largest angle (degrees) between the normals of two mesh faces centred in t; None for fewer than two."""
    n = face_normal[in_triangle(t, face_centroid)]
    if len(n) < 2:
        return None
    return float(np.degrees(np.arccos(np.clip((n @ n.T).min(), -1, 1))))


print("%s: %d domain triangles, %d folded" % (a.fit, len(T), len(folded)))
print("| triangle | corners on the boundary | mesh points inside | area covered by the mesh | data turns by (largest angle between face normals) |")
print("|---|---|---|---|---|")
margin = 0
sharp = 0
for t in folded:
    share = covered(samples(t, a.samples)).mean()
    margin += share < 0.5
    angle = turn(t)
    sharp += share >= 0.5 and angle is not None and angle > 90
    print("| %d | %d | %d | %.2f | %s |" % (t, sum(int(v) in boundary for v in T[t]), inside(t), share,
                                          "-" if angle is None else "%.1f deg" % angle))
areas = 0.5 * np.abs(np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]]))
uncovered = sum(areas[t] * (1 - covered(samples(t, 40)).mean()) for t in range(len(T)))
print("%d of %d folded triangles lie mostly (more than half) outside the mesh; the mesh leaves %.1f %% of "
      "the domain's area uncovered" % (margin, len(folded), 100 * uncovered / areas.sum()))
print("%d of the %d folded triangles inside the mesh hold data that turns by more than 90 degrees"
      % (sharp, len(folded) - margin))
