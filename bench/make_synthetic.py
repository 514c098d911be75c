#!/usr/bin/env python3
"""Synthetic scans for the fit benchmark: bare points with parameters, binary PLY.

  python3 bench/make_synthetic.py POINTS KIND OUT.ply [SEED]

KIND: smooth  - z = 0.1 sin(5u) cos(4v) + 0.05 uv over [0,1]^2 (unit-size model)
      creased - the same plus a 60 degree fold along u = 0.5 (z -= tan(30 deg) |u - 0.5|)
      holes   - smooth, with two round holes (radius 0.12 and 0.15)
      wavy    - z = 0.05 sin(30u) sin(24v): needs refinement and knot moves at 1e-3
Parameters are uniform random in the domain; positions get Gaussian noise of 1e-4 along z.
"""
import math
import random
import struct
import sys


def main():
    n, kind, out = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    seed = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    rng = random.Random(seed)
    holes = [((0.3, 0.3), 0.12), ((0.7, 0.65), 0.15)] if kind == "holes" else []
    slope = math.tan(math.radians(30)) if kind == "creased" else 0.0
    pack = struct.Struct("<5f").pack
    chunks = []
    count = 0
    while count < n:
        u, v = rng.random(), rng.random()
        if any(math.hypot(u - c[0], v - c[1]) < r for c, r in holes):
            continue
        if kind == "wavy":
            z = 0.05 * math.sin(30 * u) * math.sin(24 * v)
        else:
            z = 0.1 * math.sin(5 * u) * math.cos(4 * v) + 0.05 * u * v - slope * abs(u - 0.5)
        z += rng.gauss(0.0, 1e-4)
        chunks.append(pack(u, v, z, u, v))
        count += 1
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"comment tbs benchmark scan: {kind}, {n} points, seed {seed}\n"
              f"element vertex {n}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float u\nproperty float v\nend_header\n")
    with open(out, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(b"".join(chunks))


if __name__ == "__main__":
    main()
