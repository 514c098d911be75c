#!/usr/bin/env bash
# Install.ConsumerUsesTheInstalledPackage: installs the build into a temporary prefix, then
# builds samples/consumer against it twice, with CMake (find_package(tbs)) and with pkg-config
# (pkg-config --static tbs), and runs both: each fits, evaluates, tessellates and writes a STEP
# file.
#
#   tests/install/consumer_check.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in bin/tbs include/tbs/fit.h include/tbs/tessellate.h include/tbs/cad_export.h; do
  [ -e "$prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done
config=$(find "$prefix" -name tbsConfig.cmake)
pc=$(find "$prefix" -name tbs.pc)
[ -n "$config" ] && [ -n "$pc" ] || { echo "no CMake package or pkg-config file installed" >&2; exit 1; }
"$prefix/bin/tbs" --version

echo "== CMake: find_package(tbs)"
cmake -S "$src/samples/consumer" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release > "$work/cmake-configure.log"
cmake --build "$work/cmake" > "$work/cmake-build.log"
"$work/cmake/consumer" "$work/cmake.step"
head -c 13 "$work/cmake.step" | grep -q "ISO-10303-21;" || { echo "cmake.step is not STEP" >&2; exit 1; }

echo "== pkg-config --static tbs"
export PKG_CONFIG_PATH
PKG_CONFIG_PATH=$(dirname "$pc")
echo "tbs $(pkg-config --modversion tbs)"
# shellcheck disable=SC2046  # the flags are words
c++ -O1 "$src/samples/consumer/main.cpp" -o "$work/pc-consumer" $(pkg-config --cflags --libs --static tbs)
"$work/pc-consumer" "$work/pc.step"
head -c 13 "$work/pc.step" | grep -q "ISO-10303-21;" || { echo "pc.step is not STEP" >&2; exit 1; }
echo "consumer_check: both builds ran"
