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
import os
import struct
import sys

here = os.path.dirname(os.path.abspath(__file__))
# The corpus goes to tests/data/bad, or to the directory given (the test that checks that the
# committed corpus is what this script writes).
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "data", "bad")
cases = []


def case(name, data, expect, command="fit", what=""):
    """One file NAME with DATA (bytes or str); tbs COMMAND on it must exit with EXPECT."""
    path = os.path.join(out, name)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    cases.append({"file": name, "command": command, "exit": expect, "what": what})


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
# OFF
case("off_empty.off", "", 3, what="empty file")
case("off_header_only.off", "OFF\n", 3, what="header only")
case("off_counts_disagree.off", "OFF\n10 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3,
     what="10 vertices announced, 3 given")
case("off_count_1e12.off", "OFF\n1000000000000 1 0\n0 0 0\n", 3, what="header claims 10^12 vertices")
case("off_face_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 3, what="face index past the vertices")
case("off_negative_count.off", "OFF\n-3 1 0\n", 3, what="negative count")
# STL
case("stl_empty.stl", "", 3, what="empty file")
case("stl_truncated.stl", b"\0" * 80 + struct.pack("<I", 100) + b"\0" * 100, 3,
     what="binary, 100 triangles announced, less than one given")
case("stl_ascii_garbage.stl", "solid x\n facet normal a b c\n", 3, what="ASCII with text for numbers")
case("stl_count_huge.stl", b"\0" * 80 + struct.pack("<I", 0xFFFFFFFF), 3, what="binary, 4 billion triangles announced")
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
# .tbs
case("tbs_empty.tbs", "", 3, command="info", what="empty file")
case("tbs_not_json.tbs", "this is not a spline\n", 3, command="info", what="not JSON")
case("tbs_truncated.tbs", '{"format": "tbs", "version": 1, "degree": 3, "domain": {"vertices": [[0,0],', 3,
     command="info", what="cut short")
case("tbs_wrong_format.tbs", '{"format": "stl"}', 3, command="info", what="another format's name")
case("tbs_huge_degree.tbs", '{"format": "tbs", "version": 1, "degree": 1000000000}', 3, command="info",
     what="absurd degree")
# Paths
case("unknown.foo", "0 0 0\n1 0 0\n0 1 0\n", 3, what="unknown extension")

with open(os.path.join(out, "cases.json"), "w") as f:
    json.dump(cases, f, indent=1)
    f.write("\n")
print("%d cases in %s" % (len(cases), os.path.relpath(out)), file=sys.stderr)
