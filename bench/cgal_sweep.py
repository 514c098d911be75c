#!/usr/bin/env python3
"""Every mesh and point set of Debian's libcgal-demo data fitted by `tbs fit` at the defaults,
as a new user would try them: for docs/benchmarks.md#every-libcgal-demo-input. It looks for
hangs (a fit killed at the time limit), crashes and internal errors (a signal, or exit 5:
both bugs), unclear refusals, and the shape of what fits (folds, max_stretch, convergence), split into
open surfaces and closed ones that the fit cuts open.

    python3 bench/cgal_sweep.py [--tbs build/cli/tbs] [--timeout 300] [--largest-mb 0]
                                [--work DIR] [--markdown]

--largest-mb N skips files above N MB (0: none skipped). Prints one line per input as it
goes (to stderr), then the summary and, with --markdown, the tables for docs/benchmarks.md.
Exit status 1 when a fit hung, crashed or ended with an internal error, 0 otherwise.
"""
import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time

DATA = "/usr/share/doc/libcgal-dev/data.tar.gz"
FORMATS = (".off", ".ply", ".stl", ".obj", ".xyz", ".txt", ".pwn")
# The README's exit codes other than 5 (internal error), which is a bug like a signal.
EXPECTED = {0: "ok", 2: "bad usage", 3: "invalid input", 4: "file I/O error"}


def main():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tbs", default=os.path.join(here, "build", "cli", "tbs"))
    ap.add_argument("--timeout", type=float, default=300, help="seconds per fit before it counts as a hang")
    ap.add_argument("--largest-mb", type=float, default=0, help="skip inputs above this size (0: none)")
    ap.add_argument("--work", help="keep the fits and reports here (default: a temporary folder)")
    ap.add_argument("--markdown", action="store_true", help="print the tables of docs/benchmarks.md")
    a = ap.parse_args()

    work = a.work or tempfile.mkdtemp(prefix="tbs_cgal_sweep_")
    os.makedirs(work, exist_ok=True)
    with tarfile.open(DATA) as tar:
        members = [m for m in tar.getmembers() if m.isfile() and
                   (m.name.startswith("data/meshes/") or m.name.startswith("data/points_3/")) and
                   m.name.lower().endswith(FORMATS)]
        tar.extractall(work, members=members)
    inputs = sorted((os.path.join(work, m.name) for m in members), key=os.path.getsize)
    if a.largest_mb > 0:
        inputs = [f for f in inputs if os.path.getsize(f) <= a.largest_mb * 1e6]

    rows = []
    for path in inputs:
        name = os.path.basename(path)
        out = os.path.join(work, "fits", name)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        start = time.time()
        try:
            p = subprocess.run([a.tbs, "fit", path, "-o", out + ".tbs", "--report", out + ".json", "-q"],
                               capture_output=True, text=True, errors="replace", timeout=a.timeout)
            code, err = p.returncode, p.stderr.strip()
        except subprocess.TimeoutExpired:
            code, err = None, "killed after %.0f s" % a.timeout
        row = {"input": name, "code": code, "seconds": time.time() - start, "message": err.splitlines()[-1] if err else ""}
        if code == 0:
            r = json.load(open(out + ".json"))
            param = r.get("parameterization", {})
            row.update(folds=r["folds"], stretch=r["max_stretch"], converged=r["converged"],
                       control_points=r["control_points"], closed=param.get("seam_edges", 0) > 0,
                       kind=param.get("input", "with (u, v)"))
        rows.append(row)
        print("%-34s %-5s %7.1f s  %s" % (name, code, row["seconds"],
                                          ("folds %d, stretch %.3g, converged %s" % (row["folds"], row["stretch"], row["converged"]))
                                          if code == 0 else row["message"][:150]), file=sys.stderr, flush=True)

    hung = [r for r in rows if r["code"] is None]
    odd = [r for r in rows if r["code"] is not None and r["code"] not in EXPECTED]
    fitted = [r for r in rows if r["code"] == 0]
    refused = [r for r in rows if r["code"] in (2, 3, 4)]
    print("%d inputs: %d fitted, %d refused (exit 2-4), %d hung (> %.0f s), %d crashed or internal errors" %
          (len(rows), len(fitted), len(refused), len(hung), a.timeout, len(odd)))
    for r in hung + odd:
        print("  %s: %s %s" % (r["input"], "hung" if r["code"] is None else "exit %d" % r["code"], r["message"][:200]))
    if a.markdown:
        print()
        print("| fitted surfaces | fits | with folds | folds (median, largest) | max_stretch above 20 | not converged |")
        print("|---|---|---|---|---|---|")
        for label, group in (("open", [r for r in fitted if not r["closed"]]),
                             ("closed, cut open by the fit", [r for r in fitted if r["closed"]])):
            folds = sorted(r["folds"] for r in group)
            print("| %s | %d | %d | %s | %d | %d |" % (
                label, len(group), sum(1 for f in folds if f), "%d, %d" % (folds[len(folds) // 2], folds[-1]) if folds else "-",
                sum(1 for r in group if r["stretch"] > 20), sum(1 for r in group if not r["converged"])))
        print()
        print("| input | exit | s | folds | max_stretch | converged | control points | message (refusals) |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            if r["code"] == 0:
                print("| %s | 0 | %.1f | %d | %.3g | %s | %d | |" % (r["input"], r["seconds"], r["folds"], r["stretch"],
                                                              "yes" if r["converged"] else "no", r["control_points"]))
            else:
                msg = r["message"].replace(work + "/data/", "").replace("|", "/")
                print("| %s | %s | %.1f | | | | | %s |" % (r["input"], "hung" if r["code"] is None else r["code"],
                                                         r["seconds"], msg[:160]))
    return 1 if hung or odd else 0


if __name__ == "__main__":
    sys.exit(main())
