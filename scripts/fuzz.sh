#!/usr/bin/env bash
# Fuzzes every scan reader and the .tbs parser with libFuzzer (clang, from Debian), under
# AddressSanitizer and UndefinedBehaviorSanitizer.
#
#   scripts/fuzz.sh [-t SECONDS] [-r RUNS -s SEED] [HARNESS...]
#                                  HARNESS: ply obj off stl xyz tbs (default: all)
#
# Each harness runs SECONDS (default 60), or RUNS inputs if -r is given (then with SECONDS, if
# also given, as an upper bound), from a corpus in build-asan/fuzz/corpus/HARNESS, seeded
# with tests/fuzz/seeds, the bad-input corpus tests/data/bad, the committed regressions
# tests/data/fuzz and the samples, and kept between runs. A failing input is saved under
# build-asan/fuzz/crashes/HARNESS/ (emptied at the start of each run); the script then prints
# how to replay it and where to commit it as a regression test (tests/data/fuzz/, replayed by
# the Fuzz.*.Regressions tests).
# -s SEED fixes libFuzzer's random seed: with -r and a fresh corpus the run is repeatable, which
# is how scripts/test.sh (and so CI) runs it. Without -s every run explores differently.
# Exit status: 0 when no harness failed, 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=60 runs="" seed=0 seconds_given=0
while getopts "t:r:s:h" opt; do
  case $opt in
    t) seconds=$OPTARG seconds_given=1 ;;
    r) runs=$OPTARG ;;
    s) seed=$OPTARG ;;
    *) sed -n '2,17p' "$0"; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
all=(ply obj off stl xyz tbs)
harnesses=("${@:-${all[@]}}")
for h in "${harnesses[@]}"; do
  [[ " ${all[*]} " == *" $h "* ]] || { echo "fuzz.sh: unknown harness '$h' (one of: ${all[*]})" >&2; exit 2; }
done
[[ "$seconds" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: -t wants a positive number of seconds, got '$seconds'" >&2; exit 2; }
[[ -z "$runs" || "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: -r wants a positive number of runs, got '$runs'" >&2; exit 2; }
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "fuzz.sh: -s wants a whole number, got '$seed'" >&2; exit 2; }
limits=(-max_total_time="$seconds") budget="${seconds} s"
if [ -n "$runs" ]; then
  limits=(-runs="$runs") budget="$runs runs"
  [ "$seconds_given" = 1 ] && limits+=(-max_total_time="$seconds") budget+=" or ${seconds} s"
fi

source scripts/deps.sh
tbs_install_deps "${TBS_TEST_PACKAGES[@]}"
jobs="$(nproc 2>/dev/null || echo 2)"
cmake --preset asan >/dev/null
cmake --build --preset asan --parallel "$jobs" --target "${harnesses[@]/#/tbs_fuzz_}"

work=build-asan/fuzz
failed=()
for h in "${harnesses[@]}"; do
  corpus=$work/corpus/$h crashes=$work/crashes/$h
  rm -rf "$crashes"  # failures of earlier runs: replayed from tests/data/fuzz once kept
  mkdir -p "$corpus" "$crashes"
  # Seeds: every file whose extension is the harness's (upper or lower case).
  find tests/fuzz/seeds tests/data/bad tests/data/fuzz samples -maxdepth 1 -type f -iname "*.$h" \
    -exec cp -n -t "$corpus" {} +
  echo "fuzz.sh: $h for $budget, seed $seed (0: random) ($(find "$corpus" -type f | wc -l) inputs in the corpus)"
  status=0
  ASAN_OPTIONS="detect_leaks=1:${ASAN_OPTIONS:-}" \
    UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0" \
    "build-asan/tests/fuzz/tbs_fuzz_$h" "${limits[@]}" -seed="$seed" -timeout=10 -rss_limit_mb=2048 \
    -max_len=16384 -dict="tests/fuzz/dict/$h.dict" -artifact_prefix="$crashes/" -print_final_stats=1 \
    "$corpus" > "$work/$h.log" 2>&1 || status=$?
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|^#[0-9]+ *DONE" "$work/$h.log" | sed "s/^/  /" || true
  if [ "$status" -ne 0 ]; then
    failed+=("$h")
    echo "fuzz.sh: $h FAILED (exit $status); log: $work/$h.log" >&2
    grep -E "ERROR: |SUMMARY: |runtime error|breaks an invariant|uncaught exception|what\(\)" "$work/$h.log" | head -5 >&2 || true
    for f in "$crashes"/*; do
      [ -f "$f" ] || continue
      echo "  replay:  build-asan/tests/fuzz/tbs_fuzz_$h $f" >&2
      echo "  keep it: cp $f tests/data/fuzz/$h-$(basename "$f" | cut -c1-20).$h" >&2
    done
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: failures in: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: no failure in ${harnesses[*]} ($budget each)"
