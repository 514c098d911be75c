#!/usr/bin/env python3
"""Writes the corpus of bad inputs (tests/data/bad/) and its manifest, cases.json.

Each case is one small file that a scanner, a converter or a colleague could plausibly hand to
tbs, broken in one way. The manifest says which command reads it and the exit code tbs must
give (README.md, "Exit codes"); tests/cli/bad_inputs_check.py runs every case and also checks
that the error is one line naming the file, that no output file is left, and that it ends in
bounded time and memory. Run it again after changing a case:

    python3 scripts/make_bad_inputs.py [OUT_DIR]
"""
import json
import math
import os
import random
import struct
import sys

here = os.path.dirname(os.path.abspath(__file__))
# The corpus goes to tests/data/bad, or to the directory given (the test that checks that the
# committed corpus is what this script writes).
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "data", "bad")
cases = []


def case(name, data, expect, command="fit", what="", stdout=None, not_stdout=None):
    """One file NAME with DATA (bytes or str); tbs COMMAND on it must exit with EXPECT. A case
    that tbs repairs (EXPECT 0) names the line its summary must print (STDOUT) and, if given,
    text it must not print (NOT_STDOUT)."""
    path = os.path.join(out, name)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    c = {"file": name, "command": command, "exit": expect, "what": what}
    if stdout is not None:
        c["stdout"] = stdout
    if not_stdout is not None:
        c["not_stdout"] = not_stdout
    cases.append(c)


def ply_ascii(vertices, faces=(), count=None, props=("x", "y", "z")):
    n = len(vertices) if count is None else count
    head = "ply\nformat ascii 1.0\nelement vertex %s\n" % n
    head += "".join("property float %s\n" % p for p in props)
    if faces:
        head += "element face %d\nproperty list uchar int vertex_indices\n" % len(faces)
    head += "end_header\n"
    body = "".join(" ".join(str(c) for c in v) + "\n" for v in vertices)
    body += "".join("%d %s\n" % (len(f), " ".join(str(i) for i in f)) for f in faces)
    return head + body


def ply_binary(count, payload):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %s\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n" % count)
    return head.encode() + payload


square = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
grid = [(i, j, 0.1 * i * j) for i in range(6) for j in range(6)]


def grid_faces(n):
    """The triangles of an n x n vertex grid numbered row by row."""
    f = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            f += [(a, a + n, a + n + 1), (a, a + n + 1, a + 1)]
    return f


# A gently curved 12 x 12 sheet (a mesh that fits), and 300 scattered points on it (a cloud
# dense enough to reconstruct); numbers rounded so that the files are the same on any machine.
sheet = [(round(i / 11, 6), round(j / 11, 6), round(0.1 * math.sin(2 * i / 11) * math.cos(j / 11), 6))
         for i in range(12) for j in range(12)]
sheet_faces = grid_faces(12)
rng = random.Random(7)
cloud = []
for _ in range(300):
    u, v = rng.random(), rng.random()
    cloud.append((round(u, 6), round(v, 6), round(0.1 * math.sin(2 * u) * math.cos(v), 6), round(u, 6), round(v, 6)))


def obj(vertices, faces):
    return ("".join("v %s %s %s\n" % v for v in vertices) +
            "".join("f %s\n" % " ".join(str(i + 1) for i in f) for f in faces))


def xyz(rows):
    return "".join(" ".join(str(x) for x in r) + "\n" for r in rows)

os.makedirs(out, exist_ok=True)
# Remove the cases of the previous run only (a case may have been renamed or dropped).
try:
    for c in json.load(open(os.path.join(out, "cases.json"))):
        if os.path.exists(os.path.join(out, c["file"])):
            os.remove(os.path.join(out, c["file"]))
except (OSError, ValueError):
    pass

# PLY, ASCII
case("ply_empty.ply", "", 3, what="empty file")
case("ply_header_only.ply", ply_ascii([], count=4), 3, what="header only, 4 vertices announced")
case("ply_truncated.ply", ply_ascii(square[:2], count=4), 3, what="fewer vertices than announced")
case("ply_count_1e12.ply", ply_ascii(square, count=10**12), 3, what="header claims 10^12 vertices")
case("ply_nan.ply", ply_ascii(grid[:-1] + [("nan", 0, 0)]), 3, what="NaN coordinate")
case("ply_inf.ply", ply_ascii(grid[:-1] + [("inf", 0, 0)]), 3, what="infinite coordinate")
case("ply_1e300.ply", ply_ascii(grid[:-1] + [(1e300, 1e300, 1e300)]), 3, what="coordinate 1e300")
case("ply_text_in_number.ply", ply_ascii(grid[:-1] + [("1.0", "abc", "2.0")]), 3, what="text inside a number")
case("ply_ragged.ply", ply_ascii(grid[:-1] + [(1.0, 2.0)]), 3, what="a row with too few columns")
case("ply_face_out_of_range.ply", ply_ascii(square, faces=[(0, 1, 2), (0, 2, 9)]), 3,
     what="face index past the vertices")
case("ply_no_xyz.ply", ply_ascii(square, props=("a", "b", "c")), 3, what="no x y z properties")
case("ply_bad_format.ply", "ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n",
     3, what="unknown format")
case("ply_face_list_short.ply", ply_ascii(grid).replace(
    "end_header", "element face 1\nproperty list uchar int vertex_indices\nend_header") + "255 0 1 2\n", 3,
     what="a face announcing 255 corners, giving 3")
# PLY, binary
case("plyb_truncated.ply", ply_binary(4, struct.pack("<6f", 0, 0, 0, 1, 0, 0)), 3, what="binary, data cut short")
case("plyb_count_1e12.ply", ply_binary(10**12, struct.pack("<3f", 0, 0, 0)), 3, what="binary, 10^12 vertices claimed")
case("plyb_garbage.ply", ply_binary(40, bytes(range(256)) * 2), 3, what="binary garbage after the header")
case("plyb_nan.ply", ply_binary(40, struct.pack("<120f", *([float("nan")] * 120))), 3, what="binary NaN coordinates")
# OBJ
case("obj_empty.obj", "", 3, what="empty file")
case("obj_index_zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 3, what="face index 0 (OBJ counts from 1)")
case("obj_index_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 3, what="face index past the vertices")
case("obj_text_in_number.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", 3, what="text inside a number")
case("obj_nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", 3, what="NaN coordinate")
case("obj_binary_garbage.obj", bytes(range(256)) * 4, 3, what="binary garbage")
case("obj_1e300.obj", "v 0 0 0\nv 1 0 1e300\nv 0 1 0\nf 1 2 3\n", 3, what="coordinate 1e300")
case("obj_sliver_faces.obj", obj(grid, [(i * 6 + j, i * 6 + j + 1, i * 6 + j + 2) for i in range(6) for j in range(4)]),
     3, what="every face has collinear corners (zero area)")
# OFF
case("off_empty.off", "", 3, what="empty file")
case("off_header_only.off", "OFF\n", 3, what="header only")
case("off_counts_disagree.off", "OFF\n10 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3,
     what="10 vertices announced, 3 given")
case("off_count_1e12.off", "OFF\n1000000000000 1 0\n0 0 0\n", 3, what="header claims 10^12 vertices")
case("off_face_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 3, what="face index past the vertices")
case("off_negative_count.off", "OFF\n-3 1 0\n", 3, what="negative count")
case("off_nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", 3, what="NaN coordinate")
# STL
case("stl_empty.stl", "", 3, what="empty file")
case("stl_truncated.stl", b"\0" * 80 + struct.pack("<I", 100) + b"\0" * 100, 3,
     what="binary, 100 triangles announced, less than one given")
case("stl_ascii_garbage.stl", "solid x\n facet normal a b c\n", 3, what="ASCII with text for numbers")
case("stl_count_huge.stl", b"\0" * 80 + struct.pack("<I", 0xFFFFFFFF), 3, what="binary, 4 billion triangles announced")
case("stl_nan.stl", b"\0" * 80 + struct.pack("<I", 1) + struct.pack("<12f", 0, 0, 1, 0, 0, 0, float("nan"), 0, 0, 0, 1, 0)
     + b"\0\0", 3, what="binary, NaN corner")
case("stl_ascii_nan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 nan\nvertex 0 1 0\n"
     "endloop\nendfacet\nendsolid x\n", 3, what="ASCII, NaN corner")
# XYZ
case("xyz_empty.xyz", "", 3, what="empty file")
case("xyz_one_point.xyz", "0 0 0\n", 3, what="one point")
case("xyz_two_points.xyz", "0 0 0\n1 0 0\n", 3, what="two points")
case("xyz_identical.xyz", "1 2 3\n" * 100, 3, what="100 identical points")
case("xyz_ragged.xyz", "".join("%d %d 0\n" % (i, j) for i in range(5) for j in range(5)) + "1 2\n", 3,
     what="a row with too few columns")
case("xyz_text.xyz", "0 0 0\n1 0 zero\n0 1 0\n", 3, what="text inside a number")
case("xyz_collinear_uv.xyz", "".join("%d %d %g %g 0\n" % (i, j, 0.1 * i * j, i + j) for i in range(6) for j in range(6)),
     3, what="parameters (u, v) on a line")
case("xyz_identical_uv.xyz", "".join("%d %d 0 0.5 0.5\n" % (i, j) for i in range(6) for j in range(6)), 3,
     what="every parameter (u, v) the same")
case("xyz_binary_garbage.xyz", bytes(range(256)) * 4, 3, what="binary garbage")
case("xyz_collinear_points.xyz", "".join("%d 0 0\n" % i for i in range(50)), 3, what="points on a line")
case("xyz_inf.xyz", "0 0 0\n1 0 0\n0 1 inf\n1 1 1\n", 3, what="infinite coordinate")
case("xyz_1e300.xyz", "0 0 0\n1 0 0\n0 1 1e300\n1 1 1\n", 3, what="coordinate 1e300")
# .tbs
case("tbs_empty.tbs", "", 3, command="info", what="empty file")
case("tbs_not_json.tbs", "this is not a spline\n", 3, command="info", what="not JSON")
case("tbs_truncated.tbs", '{"format": "tbs", "version": 1, "degree": 3, "domain": {"vertices": [[0,0],', 3,
     command="info", what="cut short")
case("tbs_wrong_format.tbs", '{"format": "stl"}', 3, command="info", what="another format's name")
case("tbs_huge_degree.tbs", '{"format": "tbs", "version": 1, "degree": 1000000000}', 3, command="info",
     what="absurd degree")
tbs_ok = {"format": "tbs", "version": 1, "degree": 1, "units": "mm",
          "domain": {"vertices": [[0, 0], [1, 0], [1, 1], [0, 1]], "triangles": [[0, 1, 2], [0, 2, 3]]},
          "sub_knots": [[[-0.1, -0.1]], [[1.1, -0.1]], [[1.1, 1.1]], [[-0.1, 1.1]]],
          "control_points": [[0, 0, 0], [10, 0, 0], [10, 10, 1], [0, 10, 0]],
          "control_point_map": [[0, 1, 2], [0, 2, 3]]}


def tbs_with(**change):
    d = json.loads(json.dumps(tbs_ok))
    for key, value in change.items():
        target = d
        parts = key.split("__")
        for p in parts[:-1]:
            target = target[p]
        target[parts[-1]] = value
    return json.dumps(d)


case("tbs_missing_control_point.tbs", tbs_with(control_points=[[0, 0, 0], [10, 0, 0], [10, 10, 1]]), 3,
     command="info", what="a control point missing")
case("tbs_triangle_out_of_range.tbs", tbs_with(domain__triangles=[[0, 1, 2], [0, 2, 7]]), 3, command="info",
     what="a triangle names vertex 7 of 4")
case("tbs_huge_number.tbs", tbs_with(control_points=[[0, 0, 0], [10, 0, 0], [10, 10, 1e400], [0, 10, 0]])
     .replace("Infinity", "1e400"), 3, command="info", what="a coordinate of 1e400")
case("tbs_flipped_triangle.tbs", tbs_with(domain__triangles=[[0, 2, 1], [0, 2, 3]]), 3, command="info",
     what="a clockwise (overlapping) triangle")
case("tbs_units.tbs", tbs_with(units="furlong"), 3, command="info", what="an unknown unit")
# Repairable: tbs fits these and says in its summary what it left out or merged.
dup = list(sheet) + list(sheet)
case("ply_duplicate_vertices.ply", ply_ascii(dup, faces=[(a, b + 144, c) for a, b, c in sheet_faces]), 0,
     what="every vertex twice, the faces using both copies", stdout="duplicate vertices merged")
case("obj_some_degenerate_faces.obj", obj(sheet, sheet_faces + [(0, 0, 1), (5, 5, 5), (3, 4)]), 0,
     what="two faces with a repeated corner and one with two corners (which tinyobjloader skips) among good ones",
     stdout="degenerate faces   2 left out")
case("ply_only_two_corner_faces.ply", ply_ascii([c[:3] for c in cloud], faces=[(0, 1), (2, 3)]), 0,
     what="only faces with two corners (fitted as a point cloud)", stdout="parameterized      point cloud")
case("xyz_duplicate_points.xyz", xyz(cloud + cloud), 0, what="every point with (u, v) twice",
     stdout="points             600", not_stdout="points left out")
case("xyz_duplicate_points_no_uv.xyz", xyz([c[:3] for c in cloud] * 2), 0, what="every point twice, no (u, v)",
     stdout="points             600", not_stdout="points left out")
case("stl_nan_padded.stl", b"\0" * 80 + struct.pack("<I", 1) +
     struct.pack("<12f", 0, 0, 1, 0, 0, 0, 0, float("nan"), 0, 0, 1, 0) + b"\0\0" + b"\0" * 7, 3,
     what="binary, NaN corner, 7 bytes of padding after the last facet")
# Paths
case("unknown.foo", "0 0 0\n1 0 0\n0 1 0\n", 3, what="unknown extension")

with open(os.path.join(out, "cases.json"), "w") as f:
    json.dump(cases, f, indent=1)
    f.write("\n")
print("%d cases in %s" % (len(cases), os.path.relpath(out)), file=sys.stderr)
