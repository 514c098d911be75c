#!/usr/bin/env bash
# Installs what is missing, builds tbs (Release) and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
tbs_install_deps "${TBS_TEST_PACKAGES[@]}"
tbs_build
tbs_install_gltf_validator
cd build
ctest --output-on-failure --parallel "$(nproc 2>/dev/null || echo 2)" --timeout 900
