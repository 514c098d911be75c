#!/usr/bin/python3
"""Python.Module: the `tbs` module in Debian's python3 with NumPy (PYTHONPATH: the build's
python/ folder).

  /usr/bin/python3 tests/python/module_test.py SOURCE_DIR WORK_DIR TBS_COMMAND
"""
import json
import os
import subprocess
import sys

import numpy as np

import tbs

SOURCE, WORK, TBS = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(WORK, exist_ok=True)
failures = []


def check(condition, what):
    print(("ok    " if condition else "FAIL  ") + what)
    if not condition:
        failures.append(what)


def expect_raises(kind, what, fn):
    try:
        fn()
    except kind as e:
        check(True, "%s raises %s: %s" % (what, kind.__name__, str(e)[:100]))
        return e
    except Exception as e:  # noqa: BLE001
        check(False, "%s raises %s, not %s: %s" % (what, kind.__name__, type(e).__name__, e))
        return None
    check(False, "%s raises %s (nothing raised)" % (what, kind.__name__))
    return None


def surface(u, v):
    return np.stack([100 * u, 80 * v, 12 * np.sin(3 * u) * np.cos(2 * v)], axis=-1)


# Points with parameters on a known surface (100 x 80 mm).
rng = np.random.default_rng(3)
uv = rng.random((4000, 2))
points = surface(uv[:, 0], uv[:, 1])

check(tbs.__version__.count(".") == 2, "version %s is major.minor.patch" % tbs.__version__)

stages = []
spline = tbs.fit(points, uv, tolerance=1e-4, progress=lambda stage, message, fraction: stages.append(stage))
report = spline.report
check(report["converged"] and report["max_error"] <= 1e-4, "fit converges to 1e-4: max error %.2e" % report["max_error"])
check(report["points"] == 4000 and spline.degree == 3, "report: 4000 points, degree 3")
check("solve" in stages and "refine" in stages, "progress reports the stages: %s" % sorted(set(stages)))
check(spline.control_points.shape == (report["control_points"], 3), "control points (K, 3)")

# Evaluation against the known surface (error within the tolerance of 100 mm, doubled for
# points between the fitted ones).
grid = np.array([(u, v) for u in np.linspace(0.05, 0.95, 7) for v in np.linspace(0.05, 0.95, 7)])
value = spline.evaluate(grid)
miss = np.linalg.norm(value - surface(grid[:, 0], grid[:, 1]), axis=1).max()
check(value.shape == (49, 3) and miss < 2e-2, "evaluate (49, 3) within 0.02 mm of the surface: %.2e" % miss)
f, fu, fv = spline.evaluate(grid, derivatives=True)
h = 1e-6
fd = (spline.evaluate(grid + [h, 0]) - spline.evaluate(grid - [h, 0])) / (2 * h)
check(np.allclose(f, value) and np.abs(fu - fd).max() < 1e-4 * np.abs(fd).max(),
      "derivatives: F_u matches central differences")
outside = np.array([[0.5, 0.5], [3.0, 3.0]])
expect_raises(tbs.OutsideDomain, "evaluate outside the domain", lambda: spline.evaluate(outside))
nan = spline.evaluate(outside, outside="nan")
check(np.isnan(nan[1]).all() and np.isfinite(nan[0]).all(), "outside='nan' gives NaN only outside")
check(issubclass(tbs.OutsideDomain, ValueError) and issubclass(tbs.IoError, OSError),
      "exceptions: OutsideDomain is a ValueError, IoError an OSError")

mesh = spline.tessellate(chordal_tolerance=1e-4)
check(mesh["positions"].shape[1] == 3 and mesh["faces"].shape[1] == 3 and mesh["faces"].max() < len(mesh["positions"]),
      "tessellate: %d vertices, %d faces, indices in range" % (len(mesh["positions"]), len(mesh["faces"])))
check(np.allclose(np.linalg.norm(mesh["normals"], axis=1), 1), "tessellate: unit normals")
onsurf = np.linalg.norm(spline.evaluate(mesh["uv"]) - mesh["positions"], axis=1).max()
check(onsurf < 1e-9, "tessellate: vertices lie on the spline")

path = os.path.join(WORK, "fit.tbs")
spline.save(path)
again = tbs.load(path)
check(np.array_equal(again.evaluate(grid), value), "save + load evaluates identically")

step = os.path.join(WORK, "fit.step")
r = spline.export(step, cad_tolerance=1e-4)
check(open(step, "rb").read(13) == b"ISO-10303-21;" and r["shells"] == 1, "export STEP: %s" % r)
glb = os.path.join(WORK, "fit.glb")
r = spline.export(glb)
check(open(glb, "rb").read(4) == b"glTF" and r["triangles"] > 0, "export glb: %s" % r)
expect_raises(tbs.InvalidInput, "export to .dxf", lambda: spline.export(os.path.join(WORK, "x.dxf")))
check(not os.path.exists(os.path.join(WORK, "x.dxf")), "nothing written for .dxf")

# Cancellation: progress returning False stops the fit at its next step.
calls = []
expect_raises(tbs.Cancelled, "progress returning False",
              lambda: tbs.fit(points, uv, tolerance=1e-6, progress=lambda s, m, f: calls.append(s) or False))
check(len(calls) == 1, "cancelled after the first progress report (%d reports)" % len(calls))

# Bad input: clear errors.
expect_raises(tbs.InvalidInput, "points of shape (N, 2)", lambda: tbs.fit(points[:, :2], uv))
expect_raises(tbs.InvalidInput, "uv of another length", lambda: tbs.fit(points, uv[:10]))
expect_raises(tbs.InvalidInput, "fit without uv", lambda: tbs.fit(points, None))
expect_raises(tbs.IoError, "read_scan of a missing file", lambda: tbs.read_scan(os.path.join(WORK, "none.ply")))
bad_points = points.copy()
bad_points[5, 1] = np.nan
expect_raises(tbs.InvalidInput, "a NaN point", lambda: tbs.fit(bad_points, uv))
bad_points[5, 1] = 1e300
expect_raises(tbs.InvalidInput, "a point at 1e300", lambda: tbs.fit(bad_points, uv))
bad_uv = uv.copy()
bad_uv[3, 0] = np.inf
expect_raises(tbs.InvalidInput, "an infinite parameter", lambda: tbs.fit(points, bad_uv))
expect_raises(tbs.InvalidInput, "collinear parameters", lambda: tbs.fit(points, np.stack([uv[:, 0], uv[:, 0]], 1)))
expect_raises(tbs.InvalidInput, "a face index past the points",
              lambda: tbs.fit(points, uv, faces=np.array([[0, 1, len(points)]])))
expect_raises(tbs.InvalidInput, "a negative face index", lambda: tbs.fit(points, uv, faces=np.array([[0, -1, 2]])))
expect_raises(tbs.InvalidInput, "faces of shape (F, 4)", lambda: tbs.fit(points, uv, faces=np.zeros((2, 4), int)))
expect_raises(tbs.InvalidInput, "zero-length normals",
              lambda: tbs.fit(points, uv, normals=np.zeros_like(points)))
expect_raises(tbs.InvalidInput, "two points", lambda: tbs.fit(points[:2], uv[:2]))
expect_raises(tbs.InvalidInput, "a negative tolerance", lambda: tbs.fit(points, uv, tolerance=-1))
expect_raises(tbs.InvalidInput, "degree 9", lambda: tbs.fit(points, uv, degree=9))
expect_raises(tbs.InvalidInput, "evaluate with uv of shape (N, 3)", lambda: spline.evaluate(np.zeros((4, 3))))
# Every file of the bad-input corpus the command refuses is refused by read_scan (or by fit
# when only parameters are wrong), with the module's exceptions, never a crash.
corpus = json.load(open(os.path.join(SOURCE, "tests", "data", "bad", "cases.json")))
failing = [c for c in corpus if c["exit"] != 0 and c["command"] == "fit" and not c["file"].startswith("unknown")]
refused, without_uv = 0, []
for case in failing:
    path = os.path.join(SOURCE, "tests", "data", "bad", case["file"])
    try:
        s = tbs.read_scan(path)
        if s["uv"] is None:
            # The command refuses these while flattening, which the module does not do.
            without_uv.append(case["file"])
            continue
        tbs.fit(s["points"], s["uv"], s["normals"], s["faces"])
        check(False, "corpus %s (%s) accepted" % (case["file"], case["what"]))
    except (tbs.InvalidInput, tbs.IoError):
        refused += 1
    except Exception as e:  # noqa: BLE001
        check(False, "corpus %s raises %s: %s" % (case["file"], type(e).__name__, e))
check(refused + len(without_uv) == len(failing) and refused >= 40,
      "%d of %d failing corpus files refused by read_scan or fit; %d read without (u, v), which only the command "
      "flattens (and refuses): %s" % (refused, len(failing), len(without_uv), ", ".join(without_uv)))
expect_raises(tbs.InvalidInput, "read_scan of an unknown extension",
              lambda: tbs.read_scan(os.path.join(SOURCE, "tests", "data", "bad", "unknown.foo")))

scan = tbs.read_scan(os.path.join(SOURCE, "samples", "bracket.ply"))
check(scan["points"].shape == (40933, 3) and scan["uv"].shape == (40933, 2) and scan["faces"] is not None,
      "read_scan(samples/bracket.ply): 40933 points with uv and faces")

# The module fits a mesh as the command does: same domain, control points and errors.
bracket = tbs.fit(scan["points"], scan["uv"], faces=scan["faces"]).report
rep = os.path.join(WORK, "bracket.json")
subprocess.run([TBS, "fit", os.path.join(SOURCE, "samples", "bracket.ply"), "-o", os.path.join(WORK, "bracket.tbs"),
                "-q", "--report", rep], check=True, stdout=subprocess.DEVNULL)
cli = json.load(open(rep))
same = all(bracket[k] == cli[k] for k in ("domain_triangles", "control_points", "feature_edges", "iterations"))
check(same and abs(bracket["max_error"] - cli["max_error"]) <= 1e-12,
      "fit(points, uv, faces) of the bracket equals `tbs fit`: %d triangles, %d control points, %d feature "
      "edges, max error %.4e" % (bracket["domain_triangles"], bracket["control_points"], bracket["feature_edges"],
                                 bracket["max_error"]))

# Raw scans: tbs.parameterize computes the (u, v) that `tbs fit` computes, and fit() then gives
# the same spline as the command (libcgal-demo's mesh_with_border, and the point cloud
# poste_france, meshed first). The point cloud is parameterized twice, after other work in this
# process: its reconstruction once followed memory addresses (two meshes from three calls).
tarball = "/usr/share/doc/libcgal-dev/data.tar.gz"
if os.path.exists(tarball):
    import tarfile
    with tarfile.open(tarball) as tar:
        for member in ("data/meshes/mesh_with_border.off", "data/points_3/poste_france.xyz"):
            tar.extract(member, WORK)
    for member in ("data/meshes/mesh_with_border.off", "data/points_3/poste_france.xyz"):
        path = os.path.join(WORK, member)
        name = os.path.basename(path)
        raw = tbs.read_scan(path)
        lines = []
        p = tbs.parameterize(raw["points"], raw["faces"], raw["normals"], progress=lines.append)
        n = p["points"].shape[0]
        check(p["uv"].shape == (n, 2) and p["source"].shape == (n,) and p["source"].max() < raw["points"].shape[0]
              and np.array_equal(p["points"], raw["points"][p["source"]]) and len(lines) > 0,
              "parameterize(%s): %d points with uv, each the input point its source names, %d progress lines"
              % (name, n, len(lines)))
        if raw["faces"] is None:
            junk = [bytearray(4099 * (i % 13 + 1)) for i in range(400)]  # another heap layout
            again = tbs.parameterize(raw["points"], raw["faces"], raw["normals"])
            del junk
            check(np.array_equal(again["uv"], p["uv"]) and np.array_equal(again["source"], p["source"]),
                  "parameterize(%s) twice in one process: the same %d points and (u, v)" % (name, n))
        spline = tbs.fit(p["points"], p["uv"], normals=p["normals"], faces=p["faces"], atlas=p["atlas"])
        out, rep = os.path.join(WORK, name + ".tbs"), os.path.join(WORK, name + ".json")
        subprocess.run([TBS, "fit", path, "-o", out, "-q", "--report", rep], check=True, stdout=subprocess.DEVNULL)
        cli = json.load(open(rep))
        check(cli["parameterization"]["subdivisions"] == 0 and cli["parameterization"] == dict(p["report"], seconds=cli["parameterization"]["seconds"]),
              "%s: the command flattened the same way (%s), without subdividing" % (name, p["report"]["method"]))
        check(np.array_equal(spline.control_points, tbs.load(out).control_points),
              "%s: parameterize + fit gives the control points of `tbs fit`, bit for bit (%d)"
              % (name, spline.control_points.shape[0]))
    # A coarse mesh (patch-20, 353 vertices) whose vertices do not reach the tolerance within the
    # control-point budget: the command subdivides it to --min-points (5000) and fits again, the
    # new points as guides. parameterize(min_points=5000) returns them flagged; fit(guide=...)
    # gives the command's spline.
    with tarfile.open(tarball) as tar:
        tar.extract("data/meshes/patch-20.off", WORK)
    path = os.path.join(WORK, "data/meshes/patch-20.off")
    raw = tbs.read_scan(path)
    p = tbs.parameterize(raw["points"], raw["faces"], raw["normals"], min_points=5000)
    g = p["guide"]
    check(g is not None and g.shape == (p["points"].shape[0],) and int(g.sum()) == p["report"]["points_added"] > 0
          and not g[:p["points"].shape[0] - int(g.sum())].any(),
          "parameterize(patch-20, min_points=5000): %d points, the %d added by the subdivision flagged as guides"
          % (p["points"].shape[0], int(g.sum()) if g is not None else -1))
    spline = tbs.fit(p["points"], p["uv"], normals=p["normals"], faces=p["faces"], guide=g, atlas=p["atlas"])
    out, rep = os.path.join(WORK, "patch-20.tbs"), os.path.join(WORK, "patch-20.json")
    subprocess.run([TBS, "fit", path, "-o", out, "-q", "--report", rep], check=True, stdout=subprocess.DEVNULL)
    cli = json.load(open(rep))
    check(cli["parameterization"]["subdivisions"] > 0 and cli["guide_points"] == int(g.sum())
          and spline.report["guide_points"] == cli["guide_points"],
          "patch-20: the command subdivided too, with %d guide points" % cli["guide_points"])
    check(np.array_equal(spline.control_points, tbs.load(out).control_points),
          "patch-20: parameterize + fit(guide=...) gives the control points of `tbs fit`, bit for bit (%d)"
          % spline.control_points.shape[0])
    # patch-20's one flattening stretches more than the chart bound: it is cut into charts, and
    # the spline keeps their atlas; its outlines close and hold every chart.
    check(p["atlas"] is not None and p["report"]["charts"] > 1 and spline.report["charts"] == p["report"]["charts"]
          and len(spline.atlas["seams"]) == len(p["atlas"]["seams"]) > 0,
          "patch-20: cut into %d charts, %d seams, kept by the spline" % (p["report"]["charts"], p["report"]["seams"]))
    loops = spline.outlines()
    area = sum(0.5 * float(np.sum(l[:, 0] * np.roll(l[:, 1], -1) - np.roll(l[:, 0], -1) * l[:, 1])) for l in loops)
    uvf = p["uv"][p["faces"]]
    uv_area = float(np.sum(0.5 * ((uvf[:, 1, 0] - uvf[:, 0, 0]) * (uvf[:, 2, 1] - uvf[:, 0, 1])
                                  - (uvf[:, 1, 1] - uvf[:, 0, 1]) * (uvf[:, 2, 0] - uvf[:, 0, 0]))))
    # The fit moved the seams onto where the charts' surfaces meet (by a fraction of the
    # tolerance), so the outlines hold the charts' area up to that.
    check(abs(area - uv_area) <= 1e-3 * uv_area,
          "patch-20: the outlines hold the charts' area (%.6g against %.6g)" % (area, uv_area))
    seams = spline.check_seams(200)
    check(seams["samples"] == 200 * len(spline.atlas["seams"]) and seams["max_gap"] == seams["max_gap"]
          and seams["max_gap"] <= spline.report["tolerance_abs"],
          "patch-20: check_seams samples every seam (gap %.3g)" % seams["max_gap"])
    saved = os.path.join(WORK, "patch-20-module.tbs")
    spline.save(saved)
    back = tbs.load(saved)
    check(len(back.atlas["seams"]) == len(spline.atlas["seams"])
          and all(np.array_equal(x["a"], y["a"]) and np.array_equal(x["b"], y["b"]) and x["sharp"] == y["sharp"]
                  for x, y in zip(back.atlas["seams"], spline.atlas["seams"])),
          "patch-20: save and load keep the atlas")
    expect_raises(tbs.InvalidInput, "fit with a guide array of the wrong length",
                  lambda: tbs.fit(p["points"], p["uv"], guide=g[:-1]))
    expect_raises(tbs.InvalidInput, "parameterize with an unknown method",
                  lambda: tbs.parameterize(raw["points"], method="harmonic"))
    expect_raises(tbs.InvalidInput, "parameterize of (N, 2) points",
                  lambda: tbs.parameterize(raw["points"][:, :2]))
    expect_raises(tbs.InvalidInput, "parameterize of a mesh with a face index out of range",
                  lambda: tbs.parameterize(raw["points"][:3], np.array([[0, 1, 7]])))
else:
    check(False, "libcgal-demo's data (scripts/test.sh installs it) for the raw-scan checks")

if failures:
    sys.exit("module_test: %d failed: %s" % (len(failures), "; ".join(failures)))
print("module_test: all passed")
