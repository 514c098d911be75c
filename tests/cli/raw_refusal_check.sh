#!/usr/bin/env bash
# A raw mesh from Debian's libcgal-demo that tbs cannot flatten is refused like any bad input:
# exit code 3, one line on stderr that names the file and its component, and no output file.
#   raw_refusal_check.sh TBS_EXE WORK_DIR DATA_FILE EXPECTED_TEXT [FIT_OPTIONS...]
#     DATA_FILE inside the tarball, e.g. data/meshes/blade.off; EXPECTED_TEXT a part of the message
set -euo pipefail
tbs="$1" work="$2" file="$3" expected="$4"
shift 4
tarball=/usr/share/doc/libcgal-dev/data.tar.gz
[ -f "$tarball" ] || { echo "libcgal-demo is not installed (scripts/test.sh installs it)" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work/out"
tar xzf "$tarball" -C "$work" "$file"
code=0
"$tbs" fit "$work/$file" -o "$work/out/fit.tbs" --quiet "$@" 2> "$work/err.txt" > /dev/null || code=$?
cat "$work/err.txt"
[ "$code" = 3 ] || { echo "exit code $code, expected 3" >&2; exit 1; }
[ "$(wc -l < "$work/err.txt")" = 1 ] || { echo "expected one line on stderr" >&2; exit 1; }
grep -qF "tbs: error: $work/$file: component 1 of 1 has " "$work/err.txt" ||
  { echo "the message does not start with the file and its component" >&2; exit 1; }
grep -qF "$expected" "$work/err.txt" || { echo "the message does not say: $expected" >&2; exit 1; }
[ -z "$(ls -A "$work/out")" ] || { echo "an output file was left: $(ls "$work/out")" >&2; exit 1; }
echo "raw_refusal_check: $file refused as expected"
