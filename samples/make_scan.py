#!/usr/bin/env python3
"""Writes samples/bracket.ply: a scan-like triangle mesh of a known surface, for the demo.

The surface (millimetres) over the parameters (u, v) in [0, 1]^2, with x = 120 u, y = 90 v:
  z = 12 sin(pi v) cos(1.5 pi u) - tan(30 deg) |x - 66|
a smooth sheet folded along x = 66 (u = 0.55): the two flanks meet at a 60 degree crease.
A round hole of radius 0.13 (in u, v) around (0.28, 0.62) is cut out. The vertices are a
jittered 240 x 180 grid whose column u = 0.55 lies exactly on the crease, positions carry
Gaussian noise of 0.01 mm along z, and every vertex keeps its parameters as the PLY vertex
properties u and v. No normals: tbs estimates them. The output is deterministic (fixed seed).

Usage: python3 samples/make_scan.py [OUT.ply]
"""
import math
import random
import struct
import sys

NU, NV = 240, 180
CREASE_U = 0.55
HOLE_C, HOLE_R = (0.28, 0.62), 0.13
NOISE_MM = 0.01


def surface(u, v):
    x, y = 120.0 * u, 90.0 * v
    z = 12.0 * math.sin(math.pi * v) * math.cos(1.5 * math.pi * u)
    z -= math.tan(math.radians(30.0)) * abs(x - 120.0 * CREASE_U)
    return x, y, z


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "samples/bracket.ply"
    rng = random.Random(20261122)
    crease_col = round(CREASE_U * (NU - 1))
    # Grid parameters: columns spaced so that column crease_col is exactly u = CREASE_U.
    us = [CREASE_U * i / crease_col if i <= crease_col
          else CREASE_U + (1 - CREASE_U) * (i - crease_col) / (NU - 1 - crease_col) for i in range(NU)]
    vs = [j / (NV - 1) for j in range(NV)]
    du = 0.25 / NU
    dv = 0.25 / NV
    index = {}
    verts = []
    for j in range(NV):
        for i in range(NU):
            u, v = us[i], vs[j]
            # Jitter interior samples, but keep the crease column and the border straight.
            if 0 < j < NV - 1:
                v += rng.uniform(-dv, dv)
            if 0 < i < NU - 1 and i != crease_col:
                u += rng.uniform(-du, du)
            if math.hypot(u - HOLE_C[0], v - HOLE_C[1]) < HOLE_R:
                continue
            x, y, z = surface(u, v)
            z += rng.gauss(0.0, NOISE_MM)
            index[(i, j)] = len(verts)
            verts.append((x, y, z, u, v))
    faces = []
    for j in range(NV - 1):
        for i in range(NU - 1):
            a, b = index.get((i, j)), index.get((i + 1, j))
            c, d = index.get((i + 1, j + 1)), index.get((i, j + 1))
            if None in (a, b, c, d):
                continue
            faces.append((a, b, c))
            faces.append((a, c, d))
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        "comment tbs sample: folded sheet with a 60 degree crease and a hole (samples/make_scan.py)\n"
        f"element vertex {len(verts)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float u\nproperty float v\n"
        f"element face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    with open(out, "wb") as f:
        f.write(header.encode("ascii"))
        for x, y, z, u, v in verts:
            f.write(struct.pack("<5f", x, y, z, u, v))
        for a, b, c in faces:
            f.write(struct.pack("<B3i", 3, a, b, c))
    print(f"{out}: {len(verts)} points, {len(faces)} triangles")


if __name__ == "__main__":
    main()
