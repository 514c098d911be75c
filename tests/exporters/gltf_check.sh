#!/usr/bin/env bash
# glTF files written by `tbs convert` pass the Khronos glTF validator with no error and no
# warning: binary .glb (adaptive mesh) and .gltf (uniform mesh).
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
NODE_PATH="$modules" node "$(dirname "$0")/gltf_validate.js" "$work/wave.glb" "$work/wave.gltf"
