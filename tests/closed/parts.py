#!/usr/bin/python3
"""Closed CAD parts for the closed-object (atlas) tests, built at test time in FreeCAD.

Five exact solids (sizes in mm), made with FreeCAD's Part workbench (Debian's
freecad-python3, FreeCAD 0.20):

  egg       genus 0, smooth: an ellipsoid, semi-axes 30 x 20 x 17 (a unit sphere scaled
            non-uniformly; one rational B-spline face, exact)
  knob      genus 0, sharp edges: a cylinder r 20, h 25 with a spherical cap (sphere r 28)
            fused on top, meeting the wall at a sharp edge, and a 2 mm chamfer on the bottom rim
  torus     genus 1: R 30, r 10
  block     genus 1: a 60 x 40 x 20 box, its 4 vertical edges filleted (r 4), a through hole
            r 8 along the 20 mm thickness, both hole rims filleted (r 1.5)
  bracket2  genus 2: an 80 x 40 x 10 plate, vertical edges filleted (r 5), two through holes
            r 6, their top rims chamfered (1 mm)

For each part NAME, OUTDIR gets
  NAME.brep        the exact solid
  NAME.stl         a dense, scan-like mesh (MeshPart.meshFromShape, MaxLength = size / 60,
                   shorter if that gives under 5,000 vertices: the torus)
  NAME_cloud.xyz   36,000 points "x y z nx ny nz", uniform by area on the exact faces, exact
                   outward unit normals, moved along the normal by Gaussian noise of
                   sigma = 1e-4 x size (fixed seed: the same file on every run)
  NAME.json        name, genus, closed, volume, area, size (largest bounding-box side),
                   bbox, faces, valid (and the mesh and cloud sizes, generation seconds)

The genus is measured from a tessellation of the solid (V - E + F = 2 - 2g after merging
duplicate vertices) and must equal the intended one.

usage: /usr/bin/python3 tests/closed/parts.py OUTDIR [--only NAME ...]   (always rewrites)

As a module: build(name), genus_of(shape), sample_surface(shape, n, seed), ensure(outdir,
names), exact_size(shape), PARTS.
"""
import argparse
import json
import math
import os
import sys
import time
import zlib

for _lib in ("/usr/lib/freecad/lib", "/usr/lib/freecad-python3/lib"):
    if os.path.isdir(_lib) and _lib not in sys.path:
        sys.path.append(_lib)
import FreeCAD  # noqa: E402,F401  (FreeCAD before Part: Part alone crashes in some operations)
import Part  # noqa: E402
import MeshPart  # noqa: E402
import numpy as np  # noqa: E402
from FreeCAD import Matrix, Vector  # noqa: E402

CLOUD_POINTS = 36000
NOISE = 1e-4          # sigma of the cloud's noise, times the part's size
MESH_DIVISIONS = 60   # the STL's MaxLength is size / MESH_DIVISIONS ...
MIN_MESH_VERTICES = 5000  # ... made shorter (once) if that gives fewer vertices


def _curve(edge):
    """The edge's curve, or None (degenerate edges have none: FreeCAD raises)."""
    try:
        return edge.Curve
    except Exception:
        return None


def _circles(shape, radius, z=None, z_above=None):
    out = []
    for e in shape.Edges:
        c = _curve(e)
        if not isinstance(c, Part.Circle) or abs(c.Radius - radius) > 1e-6:
            continue
        if z is not None and abs(c.Center.z - z) > 1e-6:
            continue
        if z_above is not None and c.Center.z <= z_above:
            continue
        out.append(e)
    return out


def _vertical_edges(shape):
    return [e for e in shape.Edges
            if isinstance(_curve(e), Part.Line)
            and abs(e.Vertexes[0].Point.z - e.Vertexes[-1].Point.z) > 1e-3
            and abs(e.Vertexes[0].Point.x - e.Vertexes[-1].Point.x) < 1e-9
            and abs(e.Vertexes[0].Point.y - e.Vertexes[-1].Point.y) < 1e-9]


def make_egg():
    m = Matrix()
    m.scale(30.0, 20.0, 17.0)
    return Part.makeSphere(1.0).transformGeometry(m)


def make_knob():
    r, h, R = 20.0, 25.0, 28.0
    cylinder = Part.makeCylinder(r, h)
    zc = h - math.sqrt(R * R - r * r)          # the sphere meets the wall's top circle
    cap = Part.makeSphere(R, Vector(0, 0, zc)).common(
        Part.makeBox(4 * R, 4 * R, 2 * R, Vector(-2 * R, -2 * R, h)))
    knob = cylinder.fuse(cap).removeSplitter()
    bottom = _circles(knob, r, z=0.0)
    assert len(bottom) == 1, f"knob: {len(bottom)} bottom rims"
    return knob.makeChamfer(2.0, bottom)


def make_torus():
    return Part.makeTorus(30.0, 10.0)


def make_block():
    box = Part.makeBox(60.0, 40.0, 20.0, Vector(-30, -20, -10))
    vertical = _vertical_edges(box)
    assert len(vertical) == 4
    box = box.makeFillet(4.0, vertical)
    block = box.cut(Part.makeCylinder(8.0, 40.0, Vector(0, 0, -20)))
    rims = _circles(block, 8.0)
    assert len(rims) == 2, f"block: {len(rims)} hole rims"
    return block.makeFillet(1.5, rims)


def make_bracket2():
    plate = Part.makeBox(80.0, 40.0, 10.0, Vector(-40, -20, -5))
    vertical = _vertical_edges(plate)
    assert len(vertical) == 4
    plate = plate.makeFillet(5.0, vertical)
    for x in (-20.0, 20.0):
        plate = plate.cut(Part.makeCylinder(6.0, 30.0, Vector(x, 0, -15)))
    rims = _circles(plate, 6.0, z_above=0.0)
    assert len(rims) == 2, f"bracket2: {len(rims)} top hole rims"
    return plate.makeChamfer(1.0, rims)


# name -> (builder, intended genus)
PARTS = {
    "egg": (make_egg, 0),
    "knob": (make_knob, 0),
    "torus": (make_torus, 1),
    "block": (make_block, 1),
    "bracket2": (make_bracket2, 2),
}


def build(name):
    shape = PARTS[name][0]()
    solids = shape.Solids
    if len(solids) != 1:
        raise RuntimeError(f"{name}: {len(solids)} solids, expected 1")
    return solids[0]


def exact_bbox(shape):
    """The tight bounding box (a rational B-spline face's BoundBox is its control net's; a
    tessellated shape's optimal box is the triangulation's, widened: use a bare copy)."""
    b = shape.copy(True, False).optimalBoundingBox(False)
    return [b.XMin, b.YMin, b.ZMin, b.XMax, b.YMax, b.ZMax]


def exact_size(shape):
    b = exact_bbox(shape)
    return max(b[3] - b[0], b[4] - b[1], b[5] - b[2])


def merged_triangulation(shape, tolerance):
    """(points (V, 3), triangles (F, 3)) of the whole shape, duplicate vertices merged and
    degenerate triangles (two equal corners, at poles) dropped."""
    pts, tris = shape.tessellate(tolerance)
    P = np.array([[p.x, p.y, p.z] for p in pts], dtype=float)
    T = np.array(tris, dtype=np.int64).reshape(-1, 3)
    key = np.round(P / (tolerance * 1e-3)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    T = inverse[T]
    T = T[(T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2]) & (T[:, 2] != T[:, 0])]
    used = np.unique(T)
    remap = -np.ones(len(first), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return P[first][used], remap[T]


def genus_of(shape, tolerance=None):
    """The genus of a closed solid's boundary, from V - E + F of a merged tessellation.
    Raises if the tessellation is not a closed 2-manifold (every edge in two triangles)."""
    if tolerance is None:
        tolerance = 2e-3 * exact_size(shape)
    P, T = merged_triangulation(shape, tolerance)
    E = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    edges, uses = np.unique(E, axis=0, return_counts=True)
    if not np.all(uses == 2):
        raise RuntimeError(f"tessellation not closed: edge uses {np.bincount(uses).tolist()}")
    chi = len(P) - len(edges) + len(T)
    components = len(shape.Shells)
    if (2 * components - chi) % 2:
        raise RuntimeError(f"odd Euler characteristic {chi}")
    return (2 * components - chi) // 2


def _jacobian(surface, u, v):
    """|S_u x S_v|, the area element of the surface at (u, v)."""
    su = surface.getDN(u, v, 1, 0)
    sv = surface.getDN(u, v, 0, 1)
    return su.cross(sv).Length


def sample_surface(shape, n, seed, noise=0.0):
    """n points uniform by area on the exact faces of shape, with the exact outward unit normals.

    Each face gets a multinomial share of n by its area; its points are drawn uniformly in its
    parameter rectangle and accepted with probability |S_u x S_v| / max (rejection sampling:
    uniform by area on the true surface) when inside the trimmed face (Face.isPartOfDomain).
    The normal is Face.normalAt (it follows the face's orientation: outward on a solid).
    noise > 0 moves each point along its normal by N(0, noise) (absolute units).
    Returns (points (n, 3), normals (n, 3), face index (n,))."""
    rng = np.random.default_rng(seed)
    faces = shape.Faces
    areas = np.array([f.Area for f in faces])
    counts = rng.multinomial(n, areas / areas.sum())
    out_p, out_n, out_f = [], [], []
    for k, (face, count) in enumerate(zip(faces, counts)):
        if count == 0:
            continue
        surface = face.Surface
        u0, u1, v0, v1 = face.ParameterRange
        grid = [_jacobian(surface, u, v)
                for u in np.linspace(u0, u1, 33) for v in np.linspace(v0, v1, 33)]
        jmax = 1.25 * max(grid)
        got = 0
        tries = 0
        while got < count:
            m = max(64, 2 * (count - got))
            us = u0 + (u1 - u0) * rng.random(m)
            vs = v0 + (v1 - v0) * rng.random(m)
            keep = rng.random(m) * jmax
            for u, v, r in zip(us, vs, keep):
                j = _jacobian(surface, u, v)
                if j > jmax:
                    raise RuntimeError(f"face {k}: area element {j} above the bound {jmax}")
                if r >= j or not face.isPartOfDomain(u, v):
                    continue
                p = surface.value(u, v)
                nn = face.normalAt(u, v)
                out_p.append((p.x, p.y, p.z))
                out_n.append((nn.x, nn.y, nn.z))
                out_f.append(k)
                got += 1
                if got == count:
                    break
            tries += m
            if tries > 200 * count + 10000:
                raise RuntimeError(f"face {k}: rejection sampling stalls")
    P = np.array(out_p)
    N = np.array(out_n)
    N /= np.linalg.norm(N, axis=1)[:, None]
    F = np.array(out_f)
    order = rng.permutation(n)
    P, N, F = P[order], N[order], F[order]
    if noise > 0:
        P = P + N * rng.normal(0.0, noise, n)[:, None]
    return P, N, F


def check_outward(shape, P, N, name):
    """The normals point out: the divergence theorem (sum of p.n dA / 3 = volume) and an
    inside test on a few points."""
    area = shape.Area
    volume = np.mean(np.einsum("ij,ij->i", P, N)) * area / 3.0
    if abs(volume - shape.Volume) > 0.02 * abs(shape.Volume):
        raise RuntimeError(f"{name}: normals not outward: flux volume {volume:.1f} vs {shape.Volume:.1f}")
    eps = 1e-3 * exact_size(shape)
    for i in range(0, len(P), max(1, len(P) // 20)):
        p, nn = Vector(*P[i]), Vector(*N[i])
        if not shape.isInside(p - nn * eps, 1e-7, False) or shape.isInside(p + nn * eps, 1e-7, False):
            raise RuntimeError(f"{name}: normal at point {i} not outward")


def _used_vertices(mesh):
    """Vertices the triangles use (Mefisto may leave a few unused points; STL has none)."""
    return len(np.unique(np.array(mesh.Topology[1])))


def _mesh_genus(mesh):
    """The genus of a closed FreeCAD mesh (every edge in two triangles, else raises)."""
    T = np.array(mesh.Topology[1], dtype=np.int64)
    E = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    edges, uses = np.unique(E, axis=0, return_counts=True)
    if not np.all(uses == 2):
        raise RuntimeError(f"mesh not closed: edge uses {np.bincount(uses).tolist()}")
    chi = len(np.unique(T)) - len(edges) + len(T)
    return (2 - chi) // 2


def write_part(name, outdir):
    t0 = time.time()
    shape = build(name)
    intended = PARTS[name][1]
    size = exact_size(shape)
    valid = bool(shape.isValid())
    genus = genus_of(shape)
    if genus != intended:
        raise RuntimeError(f"{name}: genus {genus} from the tessellation, intended {intended}")
    if not shape.isClosed():
        raise RuntimeError(f"{name}: not closed")
    shape.exportBrep(os.path.join(outdir, name + ".brep"))

    t1 = time.time()
    max_length = size / MESH_DIVISIONS
    mesh = MeshPart.meshFromShape(Shape=shape, MaxLength=max_length)
    mesh_vertices = _used_vertices(mesh)
    if mesh_vertices < MIN_MESH_VERTICES:   # Mefisto meshes some periodic faces coarser
        max_length *= math.sqrt(mesh_vertices / (1.6 * MIN_MESH_VERTICES))
        mesh = MeshPart.meshFromShape(Shape=shape, MaxLength=max_length)
        mesh_vertices = _used_vertices(mesh)
    mesh.write(os.path.join(outdir, name + ".stl"))
    mesh_triangles = mesh.CountFacets
    mesh_genus = _mesh_genus(mesh)
    if mesh_genus != intended:
        raise RuntimeError(f"{name}: the STL mesh has genus {mesh_genus}, intended {intended}")
    t2 = time.time()

    seed = zlib.crc32(name.encode())
    P, N, _ = sample_surface(shape, CLOUD_POINTS, seed, noise=NOISE * size)
    check_outward(shape, P, N, name)
    with open(os.path.join(outdir, name + "_cloud.xyz"), "w") as f:
        for p, nn in zip(P, N):
            f.write(f"{p[0]:.9g} {p[1]:.9g} {p[2]:.9g} {nn[0]:.9g} {nn[1]:.9g} {nn[2]:.9g}\n")
    t3 = time.time()

    info = {
        "name": name,
        "genus": genus,
        "closed": True,
        "volume": shape.Volume,
        "area": shape.Area,
        "size": size,
        "bbox": exact_bbox(shape),
        "faces": len(shape.Faces),
        "valid": valid,
        "mesh_vertices": mesh_vertices,
        "mesh_triangles": mesh_triangles,
        "mesh_max_length": max_length,
        "mesh_genus": mesh_genus,
        "cloud_points": CLOUD_POINTS,
        "cloud_noise_sigma": NOISE * size,
        "cloud_seed": seed,
        "seconds": {"solid": t1 - t0, "mesh": t2 - t1, "cloud": t3 - t2},
    }
    with open(os.path.join(outdir, name + ".json.tmp"), "w") as f:
        json.dump(info, f, indent=1)
    os.replace(os.path.join(outdir, name + ".json.tmp"), os.path.join(outdir, name + ".json"))
    print(f"{name:9s} genus {genus}  valid {valid}  faces {len(shape.Faces):2d}  size {size:.1f}  "
          f"volume {shape.Volume:.1f}  mesh {mesh_vertices} vertices / {mesh_triangles} triangles "
          f"({t2 - t1:.1f} s)  cloud {CLOUD_POINTS} ({t3 - t2:.1f} s)  total {t3 - t0:.1f} s",
          flush=True)
    if not valid:
        raise RuntimeError(f"{name}: shape.isValid() is false")
    return info


def files_of(name, outdir):
    return [os.path.join(outdir, name + ext) for ext in (".brep", ".stl", "_cloud.xyz", ".json")]


def ensure(outdir, names=None, force=False):
    """Writes the parts whose files are missing (all with force); returns {name: info}."""
    os.makedirs(outdir, exist_ok=True)
    infos = {}
    for name in names or list(PARTS):
        if force or not all(os.path.exists(f) for f in files_of(name, outdir)):
            infos[name] = write_part(name, outdir)
        else:
            with open(os.path.join(outdir, name + ".json")) as f:
                infos[name] = json.load(f)
    return infos


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--only", nargs="+", choices=list(PARTS), metavar="NAME")
    a = ap.parse_args()
    os.makedirs(a.outdir, exist_ok=True)
    for name in a.only or list(PARTS):
        write_part(name, a.outdir)


if __name__ == "__main__":
    main()
