#!/usr/bin/env bash
# Install.ConsumerUsesTheInstalledPackage: installs the build into a temporary prefix, then
# builds samples/fit_consumer against it twice, with CMake (find_package(tbs)) and with
# pkg-config (pkg-config --static tbs), and runs both: each fits, evaluates, tessellates and
# writes a STEP file. Then the light use, samples/consumer, twice the same way
# (find_package(tbs COMPONENTS spline) and pkg-config --static tbs-spline): it links the spline
# layer alone, so its link line must name neither CHOLMOD nor tinyobjloader nor another tbs
# library; it reads samples/wave.tbs and evaluates it.
#
#   tests/install/consumer_check.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in bin/tbs include/tbs/fit.h include/tbs/scan.h include/tbs/evaluator.h include/tbs/tessellate.h \
         include/tbs/cad_export.h; do
  [ -e "$prefix/$f" ] || { echo "not installed: $f" >&2; exit 1; }
done
config=$(find "$prefix" -name tbsConfig.cmake)
pc=$(find "$prefix" -name tbs.pc)
[ -n "$(find "$prefix" -name tbs-spline.pc)" ] || { echo "no tbs-spline.pc installed" >&2; exit 1; }
[ -n "$config" ] && [ -n "$pc" ] || { echo "no CMake package or pkg-config file installed" >&2; exit 1; }
"$prefix/bin/tbs" --version

echo "== CMake: find_package(tbs)"
cmake -S "$src/samples/fit_consumer" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release > "$work/cmake-configure.log"
cmake --build "$work/cmake" > "$work/cmake-build.log"
"$work/cmake/fit_consumer" "$work/cmake.step"
head -c 13 "$work/cmake.step" | grep -q "ISO-10303-21;" || { echo "cmake.step is not STEP" >&2; exit 1; }

echo "== pkg-config --static tbs"
export PKG_CONFIG_PATH
PKG_CONFIG_PATH=$(dirname "$pc")
echo "tbs $(pkg-config --modversion tbs)"
# shellcheck disable=SC2046  # the flags are words
c++ -O1 "$src/samples/fit_consumer/main.cpp" -o "$work/pc-fit-consumer" $(pkg-config --cflags --libs --static tbs)
"$work/pc-fit-consumer" "$work/pc.step"
head -c 13 "$work/pc.step" | grep -q "ISO-10303-21;" || { echo "pc.step is not STEP" >&2; exit 1; }

# A link line of the light consumer may name the spline layer and its own dependencies only.
check_spline_only() {  # FILE WHAT
  if grep -Eo 'cholmod|tinyobjloader|tbs_(scan|fit|core|converters|exporters)|TK[A-Za-z]+' "$1"; then
    echo "$2 links more than the spline layer (above)" >&2
    exit 1
  fi
  grep -q 'tbs_spline' "$1" || { echo "$2 does not link tbs_spline" >&2; exit 1; }
}

echo "== CMake: find_package(tbs COMPONENTS spline), tbs::spline alone"
cmake -S "$src/samples/consumer" -B "$work/spline-cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release > "$work/spline-cmake-configure.log"
cmake --build "$work/spline-cmake" > "$work/spline-cmake-build.log"
link=$(find "$work/spline-cmake" -name link.txt -path '*/consumer.dir/*')
cat "$link"
check_spline_only "$link" "the CMake build of samples/consumer"
"$work/spline-cmake/consumer" "$src/samples/wave.tbs"

echo "== pkg-config --static tbs-spline"
pkg-config --libs --static tbs-spline | tee "$work/spline-pc-libs.txt"
check_spline_only "$work/spline-pc-libs.txt" "pkg-config --static tbs-spline"
# shellcheck disable=SC2046  # the flags are words
c++ -O1 "$src/samples/consumer/main.cpp" -o "$work/pc-spline-consumer" \
  $(pkg-config --cflags --libs --static tbs-spline)
"$work/pc-spline-consumer" "$src/samples/wave.tbs"
echo "consumer_check: all four builds ran"
