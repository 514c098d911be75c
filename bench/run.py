#!/usr/bin/env python3
"""The benchmark of issue 8: tbs fit on synthetic and real scans, side by side with FreeCAD's
approxSurface and OpenCASCADE's plate surface. Writes the results into docs/benchmarks.md
(between the `bench/run.py` markers) and PNG plots into docs/img/.

  python3 bench/run.py [quick|full] [--no-peers] [--no-docs] [--work DIR] [--from-json]

quick: synthetic scans of 25k and 50k points and four small libcgal-demo meshes (about 10
       minutes on 2 cores, most of it FreeCAD).
full:  adds 200k and 1M points and the head mesh (about 40 minutes).
The peers run on 10k-point versions of the synthetic scans (--peer-points) and on two of the
meshes: FreeCAD's approxSurface grows with about the 5th power of the poles per direction
(10 x 10 poles on 5k points: 1.1 s; 20 x 20: 32 s; 25 x 25 on 25k points: 636 s).

Needs a Release build with the benchmarks (build/cli/tbs, build/bench/tbs_peers: scripts/
test.sh or `cmake --build build`), GNU time, gnuplot, Debian's libcgal-demo and freecad-python3
(`apt-get install time gnuplot-nox libcgal-demo freecad-python3`).

Every fit runs alone (nothing else should run on the machine): `tbs fit --degree D --report`,
other options default (tolerance 1e-3 of the largest bounding-box side, all cores), under
GNU time for the peak resident memory.

Side by side, on the same points: the cubic tbs fit; approxSurface (ONE tensor-product cubic
B-spline, FreeCAD 0.20 defaults) with about as many control points as the tbs fit (k x k, k =
round(sqrt(control points))) and with 12 x 12; GeomPlate_BuildPlateSurface on 1,000 of the
points + GeomPlate_MakeApprox. Each surface is then measured by the same code
(`tbs_peers distance`): the distance from every input point to a fine tessellation of the
surface, over the largest side of the bounding box.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tarfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TBS = os.path.join(ROOT, "build", "cli", "tbs")
PEERS = os.path.join(ROOT, "build", "bench", "tbs_peers")
DOC = os.path.join(ROOT, "docs", "benchmarks.md")
IMG = os.path.join(ROOT, "docs", "img")
BEGIN = "<!-- bench/run.py: begin (generated; do not edit by hand) -->"
END = "<!-- bench/run.py: end -->"
CGAL_DATA = "/usr/share/doc/libcgal-dev/data.tar.gz"


def log(*a):
    print("run.py:", *a, file=sys.stderr, flush=True)


def timed(cmd, timeout=None):
    """Runs cmd under GNU time; returns (stdout, wall seconds, peak MiB) or None on failure or
    timeout (with the reason)."""
    mem = "/tmp/tbs-bench-time.txt"
    full = ["/usr/bin/time", "-f", "%e %M", "-o", mem] + cmd
    try:
        p = subprocess.run(full, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "gave up after %d s" % timeout
    if p.returncode != 0:
        return None, (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1][:200]
    wall, kb = open(mem).read().split()[-2:]
    return (p.stdout, float(wall), int(kb) / 1024), None


def fit(scan, degree, work, tag):
    out, rep = os.path.join(work, tag + ".tbs"), os.path.join(work, tag + ".json")
    r, err = timed([TBS, "fit", scan, "-o", out, "-q", "--degree", str(degree), "--report", rep])
    if r is None:
        return {"error": err}
    report = json.load(open(rep))
    report.update({"wall": r[1], "peak_mib": r[2], "tbs": out})
    return report


def distance(scan, surface, dump=None):
    r, err = timed([PEERS, "distance", scan, surface] + (["--dump", dump] if dump else []))
    if r is None:
        return {"error": err}
    return json.loads(r[0])


def synthetic(work, kind, n):
    path = os.path.join(work, "%s-%d.ply" % (kind, n))
    if not os.path.exists(path):
        subprocess.run([sys.executable, os.path.join(ROOT, "bench", "make_synthetic.py"), str(n), kind, path],
                       check=True)
    return path


def cgal_meshes(work, names):
    with tarfile.open(CGAL_DATA) as t:
        for name in names:
            dest = os.path.join(work, name)
            if not os.path.exists(dest):
                with t.extractfile("data/meshes/" + name) as src, open(dest, "wb") as dst:
                    shutil.copyfileobj(src, dst)
    return [os.path.join(work, n) for n in names]


def peers(scan, tbs_fit, work, tag, freecad_timeout):
    """The side-by-side rows for one scan: tbs (given), FreeCAD twice, the plate."""
    dump = lambda name: os.path.join(work, "%s-%s.dist" % (tag, name))  # noqa: E731
    rows = {"tbs": {"seconds": tbs_fit["seconds"], "control_points": tbs_fit["control_points"],
                    "distance": distance(scan, tbs_fit["tbs"], dump("tbs")), "dump": dump("tbs")}}
    xyz = os.path.join(work, tag + ".xyz")
    subprocess.run([PEERS, "points", scan, xyz], check=True)
    k = max(4, round(math.sqrt(tbs_fit["control_points"])))
    for name, poles in (("freecad_same", k), ("freecad_12", 12)):
        brep = os.path.join(work, "%s-%s.brep" % (tag, name))
        log(scan, name, "%d x %d poles" % (poles, poles))
        r, err = timed(["/usr/bin/python3", os.path.join(ROOT, "bench", "freecad_approx.py"), xyz, brep,
                        str(poles)], timeout=freecad_timeout)
        if r is None:
            rows[name] = {"error": err, "control_points": poles * poles}
            continue
        res = json.loads(r[0].strip().splitlines()[-1])
        rows[name] = {"seconds": res["seconds"], "control_points": res["poles_u"] * res["poles_v"],
                      "distance": distance(scan, brep, dump(name)), "dump": dump(name)}
    brep = os.path.join(work, tag + "-plate.brep")
    log(scan, "plate")
    r, err = timed([PEERS, "plate", scan, brep, "--constraints", "1000"], timeout=600)
    if r is None:
        rows["plate"] = {"error": err}
    else:
        res = json.loads(r[0])
        rows["plate"] = {"seconds": res["seconds"], "control_points": res["poles_u"] * res["poles_v"],
                         "constraints": res["constraints"], "distance": distance(scan, brep, dump("plate")),
                         "dump": dump("plate")}
    return rows


# ---------------------------------------------------------------------------------------------
# Report


def fmt_int(x):
    return "{:,}".format(int(x))


def fmt_stages(s):
    order = ["parameterize", "normals", "domain", "solve", "knots", "refine", "error"]
    keys = [k for k in order if k in s] + [k for k in s if k not in order]
    return " / ".join("%.1f" % s[k] for k in keys), "/".join(keys)


def table1(fits):
    keys = sorted({fmt_stages(f["report"]["stage_seconds"])[1] for f in fits if "error" not in f["report"]})
    header = keys[0].replace("/", " / ") if len(keys) == 1 else "time per stage"
    lines = ["| scan | points | degree | domain triangles | control points | max error | RMS error | "
             "converged | time (s) | %s (s) | peak memory (MiB) |" % header,
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for f in fits:
        r = f["report"]
        if "error" in r:
            lines.append("| %s | %s | %d | failed: %s | | | | | | | |" % (f["name"], fmt_int(f["points"]), f["degree"],
                                                                    r["error"].replace("|", "\\|")))
            continue
        stages, order = fmt_stages(r["stage_seconds"])
        lines.append("| %s | %s | %d | %s | %s | %.2e | %.2e | %s | %.1f | %s | %.0f |" % (
            f["name"], fmt_int(r["points"]), r["degree"], fmt_int(r["domain_triangles"]),
            fmt_int(r["control_points"]), r["max_error"], r["rms_error"],
            "yes" if r["converged"] else "no (%s)" % r["stop_reason"], r["seconds"],
            stages if len(keys) == 1 else order + ": " + stages, r["peak_mib"]))
    return lines


def side_by_side(cases):
    lines = ["| scan | surface | control points | max distance | RMS distance | time (s) | "
             "max / tbs | RMS / tbs | time / tbs | mesh chordal dev. |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    labels = {"tbs": "tbs (triangular, cubic)", "freecad_same": "approxSurface, as many poles",
              "freecad_12": "approxSurface, 12 x 12", "plate": "plate (1,000 constraints)"}
    for c in cases:
        base = c["rows"]["tbs"]
        for key in ("tbs", "freecad_same", "freecad_12", "plate"):
            r = c["rows"].get(key)
            if r is None:
                continue
            if "error" in r:
                cps = fmt_int(r["control_points"]) if "control_points" in r else ""
                lines.append("| %s | %s | %s | %s | | | | | | |" % (c["name"], labels[key], cps, r["error"]))
                continue
            d, b = r["distance"], base["distance"]
            if "error" in d or "error" in b:
                lines.append("| %s | %s | %s | distance failed | | | | | | |" % (c["name"], labels[key],
                                                                             fmt_int(r["control_points"])))
                continue
            lines.append("| %s | %s | %s | %.2e | %.2e | %.2f | %.2f | %.2f | %.1f | %.1e |" % (
                c["name"], labels[key], fmt_int(r["control_points"]), d["max"], d["rms"], r["seconds"],
                d["max"] / b["max"], d["rms"] / b["rms"], r["seconds"] / max(base["seconds"], 1e-3),
                d["chordal_deviation"]))
    return lines


def distance_maps(cases):
    """Per scan, one PNG with a panel per surface: every point at its (x, y), coloured by its
    distance to the surface. Shows what a peer does at a crease or over holes."""
    made = []
    for c in cases:
        panels = [(k, r) for k, r in c["rows"].items() if k in ("tbs", "freecad_same", "plate")
                  and os.path.exists(r.get("dump", ""))]
        if len(panels) < 2:
            continue
        slug = re.sub(r"[^a-z0-9]+", "-", c["name"].lower()).strip("-")
        png = os.path.join(IMG, "distance-%s.png" % slug)
        titles = {"tbs": "tbs", "freecad_same": "approxSurface", "plate": "plate"}
        cmds = ["set terminal pngcairo size %d,420 noenhanced" % (380 * len(panels)), "set output '%s'" % png,
                "set multiplot layout 1,%d title '%s: distance from each point to the surface "
                "(of the model size)'" % (len(panels), c["name"]),
                "set logscale cb", "set cbrange [1e-5:1e-1]", "set format cb '%.0e'", "unset key",
                "set size ratio -1", "set palette defined (0 'blue', 1 'cyan', 2 'yellow', 3 'red')",
                "set xtics 0.5", "set ytics 0.5"]
        for k, r in panels:
            cmds += ["set title '%s, max %.1e'" % (titles[k], r["distance"]["max"]),
                     "plot '%s' using 1:2:($3 < 1e-5 ? 1e-5 : $3) with points pt 7 ps 0.15 palette" % r["dump"]]
        cmds.append("unset multiplot")
        subprocess.run(["gnuplot", "-e", "; ".join(cmds)], check=True)
        made.append(png)
    return made


def plots(fits, work):
    os.makedirs(IMG, exist_ok=True)
    if not shutil.which("gnuplot"):
        log("gnuplot not found: no plots (apt-get install gnuplot-nox)")
        return []
    made = []
    # Time against points: the synthetic scans, one line per kind and degree.
    series = {}
    for f in fits:
        r = f["report"]
        if "error" in r or f["kind"] == "mesh":
            continue
        series.setdefault("%s, degree %d" % (f["kind"], f["degree"]), []).append((r["points"], r["seconds"]))
    dat, plot = [], []
    for i, (label, pts) in enumerate(sorted(series.items())):
        path = os.path.join(work, "time-%d.dat" % i)
        with open(path, "w") as fh:
            for p, s in sorted(pts):
                fh.write("%d %g\n" % (p, s))
        plot.append("'%s' using 1:2 with linespoints title '%s'" % (path, label))
    if plot:
        png = os.path.join(IMG, "time-vs-points.png")
        script = ("set terminal pngcairo size 800,560 noenhanced; set output '%s'; set logscale xy; set grid;"
                  "set xlabel 'points'; set ylabel 'fit time (s)'; set key top left;"
                  "set title 'tbs fit: time against points (2 cores)'; plot %s" % (png, ", ".join(plot)))
        subprocess.run(["gnuplot", "-e", script], check=True)
        made.append(png)
    # Error against control points: the refinement rounds of every fit that took more than one.
    plot = []
    for i, f in enumerate(fits):
        r = f["report"]
        if "error" in r or len(r.get("rounds", [])) < 2:
            continue
        path = os.path.join(work, "rounds-%d.dat" % i)
        with open(path, "w") as fh:
            for rd in r["rounds"]:
                fh.write("%d %g %g\n" % (rd["control_points"], rd["max_error"], rd["rms_error"]))
        label = f["name"] if f["kind"] == "mesh" else "%s, %s points" % (f["kind"], fmt_int(f["points"]))
        plot.append("'%s' using 1:2 with linespoints title '%s, degree %d'" % (path, label, f["degree"]))
    if plot:
        png = os.path.join(IMG, "error-vs-control-points.png")
        script = ("set terminal pngcairo size 1100,600 noenhanced; set output '%s'; set logscale xy; set grid;"
                  "set xlabel 'control points'; set ylabel 'max error (of the largest bounding-box side)';"
                  "set key outside right; set title 'tbs fit: max error after each refinement round';"
                  "plot %s, 1e-3 with lines dashtype 2 lc rgb 'black' title 'tolerance'" % (png, ", ".join(plot)))
        subprocess.run(["gnuplot", "-e", script], check=True)
        made.append(png)
    return made


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return "%d cores (%s)" % (os.cpu_count() or 0, cpu)


def write_doc(mode, fits, cases, pngs, maps, argv):
    lines = [BEGIN, "", "Produced %s on %s by" % (time.strftime("%Y-%m-%d"), machine()), "", "```sh",
             "python3 bench/run.py " + " ".join(argv), "```", ""]
    lines += ["### Fits: the paper's Table 1 columns, peak memory and time per stage", ""]
    lines += table1(fits)
    lines += ["", "Errors are |p - F(u)| over the largest bounding-box side, as in the paper and in "
              "`tbs fit`'s report; times are the fit's own (`seconds` in the report: reading the scan "
              "and writing the `.tbs` excluded), peak memory is the whole command's (GNU time).", ""]
    for png in pngs:
        lines += ["![%s](img/%s)" % (os.path.basename(png)[:-4].replace("-", " "), os.path.basename(png)), ""]
    if cases:
        lines += ["### Side by side: same points, same error measure", ""]
        lines += side_by_side(cases)
        lines += ["", "Distances: from every input point to a tessellation of each surface "
                  "(`tbs_peers distance`, the same code for all), over the largest bounding-box side. "
                  "The last column is the tessellation's own largest chordal deviation (same scale), "
                  "measured over the whole surface: a distance can be off by at most that much.",
                  "Times: the fitting call alone (tbs: the report's `seconds`; FreeCAD: the "
                  "`approxSurface` call; plate: `Perform` + `MakeApprox`). Ratios above 1 favour tbs.", ""]
        for png in maps:
            lines += ["![%s](img/%s)" % (os.path.basename(png)[:-4].replace("-", " "), os.path.basename(png)), ""]
    lines.append(END)
    text = open(DOC).read()
    block = "\n".join(lines)
    if BEGIN in text and END in text:
        text = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END), lambda m: block, text, flags=re.S)
    else:
        text = text.rstrip("\n") + "\n\n## Benchmark run (bench/run.py)\n\n" + block + "\n"
    tmp = DOC + ".tmp"
    open(tmp, "w").write(text)
    os.replace(tmp, DOC)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mode", nargs="?", default="quick", choices=["quick", "full"])
    ap.add_argument("--no-peers", action="store_true", help="skip FreeCAD and the plate")
    ap.add_argument("--no-docs", action="store_true", help="print the tables, leave docs/ alone")
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "bench-run"))
    ap.add_argument("--freecad-timeout", type=int, default=1200, help="seconds per approxSurface call")
    ap.add_argument("--peer-points", type=int, default=10000, help="points of the synthetic scans for the peers")
    ap.add_argument("--from-json", action="store_true",
                    help="only rewrite docs/benchmarks.md and the plots from the last run's results in --work")
    args = ap.parse_args()
    if args.from_json:
        fits = json.load(open(os.path.join(args.work, "fits.json")))
        sbs = os.path.join(args.work, "side-by-side.json")
        cases = json.load(open(sbs)) if os.path.exists(sbs) else []
        pngs, maps = plots(fits, args.work), distance_maps(cases)
        write_doc(args.mode, fits, cases, pngs, maps, json.load(open(os.path.join(args.work, "argv.json"))))
        log("rewrote", DOC, *(pngs + maps))
        return
    for tool in (TBS, PEERS, "/usr/bin/time"):
        if not os.access(tool, os.X_OK):
            sys.exit("run.py: %s is missing (build with scripts/test.sh; apt-get install time)" % tool)
    os.makedirs(args.work, exist_ok=True)

    sizes = [25000, 50000] + ([200000, 1000000] if args.mode == "full" else [])
    meshes = ["mesh_with_border.off", "cylinder.off", "mask_cone.off", "patch-20.off"]
    if args.mode == "full":
        meshes.append("head.off")
    fits = []
    for kind in ("smooth", "creased", "holes"):
        for n in sizes:
            scan = synthetic(args.work, kind, n)
            for degree in (3, 4):
                log("fit", kind, n, "degree", degree)
                fits.append({"name": "%s (synthetic)" % kind, "kind": kind, "points": n, "degree": degree,
                             "scan": scan, "report": fit(scan, degree, args.work, "%s-%d-%d" % (kind, n, degree))})
    for scan in cgal_meshes(args.work, meshes):
        for degree in (3, 4):
            name = os.path.basename(scan)
            log("fit", name, "degree", degree)
            fits.append({"name": name + " (libcgal-demo)", "kind": "mesh", "points": 0, "degree": degree,
                         "scan": scan, "report": fit(scan, degree, args.work, "%s-%d" % (name, degree))})

    cases = []
    if not args.no_peers:
        n = args.peer_points
        targets = [("%s, %s points (synthetic)" % (kind, fmt_int(n)), synthetic(args.work, kind, n))
                   for kind in ("smooth", "creased", "holes")]
        targets += [("%s (libcgal-demo)" % os.path.basename(s), s)
                    for s in cgal_meshes(args.work, ["mesh_with_border.off", "cylinder.off"])]
        for name, scan in targets:
            tag = os.path.basename(scan).rsplit(".", 1)[0] + "-peers"
            log("side by side:", name)
            base = fit(scan, 3, args.work, tag)
            if "error" in base:
                cases.append({"name": name, "rows": {"tbs": {"error": base["error"], "control_points": 0}}})
                continue
            cases.append({"name": name, "rows": peers(scan, base, args.work, tag, args.freecad_timeout)})
        json.dump(cases, open(os.path.join(args.work, "side-by-side.json"), "w"), indent=1)
    json.dump(fits, open(os.path.join(args.work, "fits.json"), "w"), indent=1)
    json.dump(sys.argv[1:], open(os.path.join(args.work, "argv.json"), "w"))

    pngs = []
    if not args.no_docs and shutil.which("gnuplot"):
        pngs = plots(fits, args.work)
        maps = distance_maps(cases)
    else:
        maps = []
    if args.no_docs:
        print("\n".join(table1(fits)))
        if cases:
            print("\n".join(side_by_side(cases)))
    else:
        write_doc(args.mode, fits, cases, pngs, maps, sys.argv[1:])
        log("wrote", DOC, *(pngs + maps))


if __name__ == "__main__":
    main()
