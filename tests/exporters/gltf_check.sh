#!/usr/bin/env bash
# glTF files written by `tbs convert` pass the Khronos glTF validator with no error and no
# warning: binary .glb (adaptive mesh), .gltf with its .bin (uniform mesh), and a .glb with the
# COLOR_0 error heat map of a fitted scan.
#   gltf_check.sh TBS_EXE SOURCE_DIR WORK_DIR NODE_MODULES_DIR
set -euo pipefail
tbs="$1" source="$2" work="$3" modules="$4"
if [ ! -f "$modules/gltf-validator/package.json" ]; then
  echo "the Khronos glTF validator is not installed in $modules: run scripts/test.sh (it installs it)" >&2
  exit 1
fi
mkdir -p "$work"
"$tbs" convert "$source/samples/wave.tbs" "$work/wave.glb" --quiet
"$tbs" convert "$source/samples/wave.tbs" "$work/wave.gltf" --resolution 3 --quiet
"$tbs" fit "$source/samples/bracket.ply" -o "$work/bracket.tbs" --keep-points --quiet > /dev/null
"$tbs" convert "$work/bracket.tbs" "$work/heat.glb" --color-by error --quiet
test -f "$work/wave.bin"
NODE_PATH="$modules" node "$(dirname "$0")/gltf_validate.js" "$work/wave.glb" "$work/wave.gltf" "$work/heat.glb"
