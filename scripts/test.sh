#!/usr/bin/env bash
# Installs what is missing, builds tbs and runs every test, twice:
#   1. the Release build (build/): every test;
#   2. the `asan` preset (build-asan/, clang with AddressSanitizer and UndefinedBehaviorSanitizer):
#      every test but the heavy raw-scan fits, then each libFuzzer harness for a few seconds.
#
#   scripts/test.sh [--release-only]
set -euo pipefail
cd "$(dirname "$0")/.."
release_only=0
case "${1:-}" in
  "") ;;
  --release-only) release_only=1 ;;
  *) echo "usage: scripts/test.sh [--release-only]" >&2; exit 2 ;;
esac
source scripts/deps.sh
tbs_install_deps "${TBS_TEST_PACKAGES[@]}"
jobs="$(nproc 2>/dev/null || echo 2)"
tbs_build
tbs_install_gltf_validator
(cd build && ctest --output-on-failure --parallel "$jobs" --timeout 900)
[ "$release_only" = 1 ] && exit 0

echo "tbs: the sanitized build (CMake preset asan, in build-asan/)" >&2
cmake --preset asan >/dev/null
cmake --build --preset asan --parallel "$jobs"
ctest --preset asan --parallel "$jobs"
# A short, repeatable fuzz run (fixed seed and number of inputs, 60 s at most per harness); run
# scripts/fuzz.sh without -r/-s to explore.
scripts/fuzz.sh -r "${TBS_FUZZ_RUNS:-40000}" -s 1 -t 60
