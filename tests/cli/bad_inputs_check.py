#!/usr/bin/env python3
"""Runs tbs on every case of tests/data/bad/cases.json (written by scripts/make_bad_inputs.py)
and on a missing file and a directory. Each must end within 60 s and 2 GiB of address space,
with the exit code the manifest documents, one line on stderr of the form
"tbs: error: ..." that names the file, and no file left in the output directory. A case that
tbs repairs (exit 0) must instead write the .tbs, print nothing on stderr, and name the repair
in its summary (the manifest's "stdout" text).

    bad_inputs_check.py TBS_EXE SOURCE_DIR WORK_DIR [--markdown] [--sanitized]

With --sanitized (an AddressSanitizer build, which reserves terabytes of address space) the
memory bound is ASan's resident-memory limit of 2 GiB instead of the address-space limit.

With --markdown it also prints the table of docs/robustness.md (run it from SOURCE_DIR with
SOURCE_DIR = . so that the messages show paths relative to it).
"""
import json
import os
import resource
import shutil
import subprocess
import sys

tbs, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
markdown = "--markdown" in sys.argv[4:]
sanitized = "--sanitized" in sys.argv[4:]
env = dict(os.environ)
if sanitized:
    env["ASAN_OPTIONS"] = ":".join(filter(None, [env.get("ASAN_OPTIONS", ""), "hard_rss_limit_mb=2048"]))
rows = []
bad = os.path.join(source, "tests", "data", "bad")
cases = json.load(open(os.path.join(bad, "cases.json")))
cases.append({"file": "no_such_file.ply", "command": "fit", "exit": 4, "what": "missing file", "path": os.path.join(work, "no_such_file.ply")})
os.makedirs(os.path.join(work, "a_directory.ply"), exist_ok=True)
cases.append({"file": "a_directory.ply", "command": "fit", "exit": 4, "what": "a directory", "path": os.path.join(work, "a_directory.ply")})


def limits():
    if sanitized:
        return
    resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))


failures = []
for c in cases:
    path = c.get("path", os.path.join(bad, c["file"]))
    out_dir = os.path.join(work, "out_" + c["file"])
    shutil.rmtree(out_dir, ignore_errors=True)
    os.makedirs(out_dir)
    if c["command"] == "fit":
        cmd = [tbs, "fit", path, "-o", os.path.join(out_dir, "out.tbs"), "-q"]
    else:
        cmd = [tbs, c["command"], path]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, errors="replace", timeout=60, preexec_fn=limits,
                           env=env)
    except subprocess.TimeoutExpired:
        failures.append("%s (%s): no answer within 60 s" % (c["file"], c["what"]))
        continue
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    problems = []
    if r.returncode != c["exit"]:
        problems.append("exit %d, documented %d" % (r.returncode, c["exit"]))
    left = os.listdir(out_dir)
    if c["exit"] == 0:
        # Repaired: fitted, nothing on stderr (-q), and the summary says what was repaired.
        said = [l for l in r.stdout.splitlines() if c["stdout"] in l]
        if lines:
            problems.append("%d lines on stderr" % len(lines))
        if not said:
            problems.append("the summary lacks '%s'" % c["stdout"])
        if c.get("not_stdout") and c["not_stdout"] in r.stdout:
            problems.append("the summary says '%s'" % c["not_stdout"])
        if left != ["out.tbs"]:
            problems.append("files written: %s, expected out.tbs" % left)
        message = said[0] if said else "(no summary line)"
    else:
        if len(lines) != 1:
            problems.append("%d lines on stderr" % len(lines))
        elif not lines[0].startswith("tbs: error: ") or c["file"] not in lines[0]:
            problems.append("the message does not name the file")
        if left:
            problems.append("left files: %s" % left)
        message = lines[-1] if lines else "(no message)"
    print("%-28s exit %d  %s" % (c["file"], r.returncode, message))
    rows.append("| `%s` | %s | %s | %d | %s |" % (c["file"], c["what"], c["command"], r.returncode,
                                                 message.replace("|", "\\|").replace(work, "WORK")))
    if problems:
        failures.append("%s (%s): %s; stderr: %s" % (c["file"], c["what"], "; ".join(problems), r.stderr.strip()[:400]))

if markdown:
    print("\n| file | what is wrong | command | exit | message (for exit 0: the summary line) |\n|---|---|---|---|---|")
    print("\n".join(rows))
if failures:
    print("\n%d of %d cases failed:" % (len(failures), len(cases)), file=sys.stderr)
    for f in failures:
        print("  " + f, file=sys.stderr)
    sys.exit(1)
print("all %d cases: documented exit code; failures one line naming the file and nothing left behind, repairs fitted and named in the summary" % len(cases))
