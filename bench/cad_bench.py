#!/usr/bin/env python3
"""CAD export figures for docs/benchmarks.md: faces, file size, time per stage and deviation of
the three STEP forms (region faces, triangle patches, exact pieces) for the bracket sample,
synthetic smooth / creased / holed scans and the libcgal-demo raw scans.

  python3 bench/cad_bench.py [quick|full] [--build DIR] [--work DIR] [--timeout S] [--forms F,F]
                             [--only NAME,NAME] [--triangle-patch quads|degenerate]

quick: the bracket, the 50k synthetic scans and the RawScan meshes; full adds the 1M synthetic
scans. Each input is fitted with `tbs fit IN -o OUT.tbs --tolerance 1e-3` (the bracket with
its demo options), then converted by `tbs convert OUT.tbs OUT.step --faces F --report R.json`
with every other option at its default. A conversion that takes longer than --timeout (600 s)
is stopped and reported as such. --only keeps the inputs whose name contains one of the given
words (e.g. --only bracket,smooth,mask_cone). --triangle-patch is passed on to `tbs convert`
(triangle patches and exact pieces; the RawScan tests use degenerate). Prints a Markdown table;
"peak GB" is the conversion's largest resident set (wait4's ru_maxrss).
"""
import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time

here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RAW = ["meshes/mask_cone.off", "meshes/mesh_with_border.off", "meshes/cylinder.off", "meshes/head.off",
       "meshes/lion.off", "meshes/patch-20.off", "meshes/sphere966.off", "points_3/poste_france.xyz"]


def fit(tbs, source, out, extra):
    if os.path.exists(out):
        return
    t0 = time.time()
    subprocess.run([tbs, "fit", source, "-o", out, "--quiet", *extra], check=True, stdout=subprocess.DEVNULL)
    print(f"fitted {os.path.basename(source)} in {time.time() - t0:.1f} s", file=sys.stderr)


def run_measured(cmd, timeout):
    """Runs cmd; returns (exit code, stderr, peak resident set in bytes), or None on timeout."""
    with tempfile.TemporaryFile() as err:
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
        deadline = time.time() + timeout
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.time() > deadline:
                p.kill()
                os.wait4(p.pid, 0)
                return None
            time.sleep(0.05)
        p.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait again
        err.seek(0)
        return p.returncode, err.read().decode(errors="replace"), usage.ru_maxrss * 1024


def convert(tbs, spline, form, timeout, triangle_patch):
    out = spline[:-4] + f"-{form}.step"
    report = out + ".json"
    t0 = time.time()
    extra = ["--triangle-patch", triangle_patch] if triangle_patch else []
    r = run_measured([tbs, "convert", spline, out, "--faces", form, "--report", report, "--quiet", *extra], timeout)
    if r is None:
        return {"timeout": timeout}
    wall = time.time() - t0
    code, stderr, peak = r
    if code != 0:
        return {"error": stderr.strip().splitlines()[-1] if stderr.strip() else f"exit {code}"}
    rep = json.load(open(report))
    rep["wall"] = wall
    rep["peak"] = peak
    os.remove(out)
    return rep


def row(name, form, rep):
    if "timeout" in rep:
        return f"| {name} | {form} | stopped after {rep['timeout']} s | | | | | | |"
    if "error" in rep:
        return f"| {name} | {form} | failed: {rep['error']} | | | | | | |"
    st = rep["stage_seconds"]
    first = st.get("regions", st.get("patches", st.get("extract", 0)))
    stages = f"{first:.2f} / {st['shell']:.2f} / {st['check']:.2f} / {st['translate']:.2f} / {st['write']:.2f}"
    dev = rep.get("max_position_deviation")
    dev_text = "exact" if dev is None else f"{dev:.3g}" + ("" if dev <= rep["cad_tolerance"] else " (over)")
    count = rep["regions"]["faces"] if form == "regions" else rep.get("patches", "")
    return (f"| {name} | {form} | {count} | {rep['faces']:,} | {rep['file_bytes'] / 1e6:.2f} | {rep['wall']:.2f} | "
            f"{rep['peak'] / 1e9:.2f} | "
            f"{stages} | {dev_text} (tol {rep['cad_tolerance']:.3g}) |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", nargs="?", default="quick", choices=["quick", "full"])
    ap.add_argument("--build", default=os.path.join(here, "build"))
    ap.add_argument("--work", default=os.path.join(here, "build", "cad_bench"))
    ap.add_argument("--timeout", type=float, default=600)
    ap.add_argument("--forms", default="regions,triangles,exact")
    ap.add_argument("--only", default="")
    ap.add_argument("--triangle-patch", default="", choices=["", "quads", "degenerate"])
    a = ap.parse_args()
    tbs = os.path.join(a.build, "cli", "tbs")
    os.makedirs(a.work, exist_ok=True)
    inputs = []
    bracket = os.path.join(a.work, "bracket.tbs")
    fit(tbs, os.path.join(here, "samples", "bracket.ply"), bracket, ["--units", "mm"])
    inputs.append(("bracket (samples/bracket.ply)", bracket))
    sizes = [50_000] + ([1_000_000] if a.mode == "full" else [])
    for n in sizes:
        for kind in ("smooth", "creased", "holes"):
            ply = os.path.join(a.work, f"{kind}-{n}.ply")
            if not os.path.exists(ply):
                subprocess.run([sys.executable, os.path.join(here, "bench", "make_synthetic.py"), str(n), kind, ply],
                               check=True)
            spline = ply[:-4] + ".tbs"
            fit(tbs, ply, spline, ["--tolerance", "1e-3"])
            inputs.append((f"{kind}, {n:,} points", spline))
    with tarfile.open("/usr/share/doc/libcgal-dev/data.tar.gz") as tar:
        for name in RAW:
            member = "data/" + name
            path = os.path.join(a.work, member)
            if not os.path.exists(path):
                tar.extract(member, a.work)
            spline = os.path.join(a.work, os.path.splitext(os.path.basename(name))[0] + ".tbs")
            fit(tbs, path, spline, ["--tolerance", "1e-3"])
            inputs.append((os.path.basename(name), spline))
    print("| input | form | regions / patches | faces | STEP MB | time s | peak GB | stages s (faces / shell / check / translate / write) | max deviation |")
    print("|---|---|---|---|---|---|---|---|---|")
    only = [w for w in a.only.split(",") if w]
    for name, spline in inputs:
        if only and not any(w in name for w in only):
            continue
        for form in a.forms.split(","):
            print(row(name, form, convert(tbs, spline, form, a.timeout, a.triangle_patch)), flush=True)


if __name__ == "__main__":
    main()
