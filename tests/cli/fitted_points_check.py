#!/usr/bin/env python3
"""Every point a fit counts as fitted evaluates through `tbs eval` after the .tbs round trip.

  fitted_points_check.py TBS FIT.tbs REPORT.json

FIT.tbs was written by `tbs fit --keep-points --report REPORT.json`: it holds the points and the
(u, v) each was fitted at. Their (u, v) go through `tbs eval --outside nan`. Passes when
  - the points outside are among the report's excluded_points (0-based), and every other one
    evaluates within the report's max_error_abs of its point, the distance the fit measured
    there (excluded points that lie inside the domain evaluate too, at any distance).
Otherwise it names the first point that does not.
"""
import json
import math
import subprocess
import sys


def main():
    tbs, spline, report = sys.argv[1:4]
    r = json.load(open(report))
    f = json.load(open(spline))
    pts, uv = f["points"]["positions"], f["points"]["parameters"]
    # A subdivided mesh's guide points (the last ones) are not kept.
    assert len(pts) == len(uv) == r["points"] - r["guide_points"], (len(pts), len(uv), r["points"], r["guide_points"])
    text = "".join("%.17g %.17g\n" % (u, v) for u, v in uv)
    run = subprocess.run([tbs, "eval", spline, "--outside", "nan"], input=text, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("tbs eval failed (exit %d): %s" % (run.returncode, run.stderr.strip()))
    lines = run.stdout.splitlines()
    assert len(lines) == len(uv), (len(lines), len(uv))
    excluded = set(r["excluded_points"])
    assert len(excluded) == r["points_excluded"], (len(excluded), r["points_excluded"])
    outside = []
    worst = 0.0
    limit = r["max_error_abs"] * (1 + 1e-9) + 1e-12
    for i, line in enumerate(lines):
        x = [float(t) for t in line.split()]
        if any(math.isnan(c) for c in x):
            outside.append(i)
            if i not in excluded:
                sys.exit("point %d at (u, v) = (%.17g, %.17g) was fitted but tbs eval finds it outside the "
                         "domain" % (i + 1, uv[i][0], uv[i][1]))
            continue
        if i in excluded:
            continue
        d = math.dist(x, pts[i])
        worst = max(worst, d)
        if d > limit:
            sys.exit("point %d at (u, v) = (%.17g, %.17g) evaluates %.6g from its point, more than the "
                     "report's max_error_abs %.6g" % (i + 1, uv[i][0], uv[i][1], d, r["max_error_abs"]))
    if outside and "outside the domain" not in run.stderr:
        sys.exit("tbs eval --outside nan gave no warning for %d point(s) outside" % len(outside))
    print("%d points: %d fitted, all evaluate (largest distance %.3g, report max_error_abs %.3g); %d excluded, "
          "%d of them outside the domain" % (len(uv), len(uv) - len(excluded), worst, r["max_error_abs"],
                                             len(excluded), len(outside)))


if __name__ == "__main__":
    main()
