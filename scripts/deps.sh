# Shared by scripts/test.sh and scripts/demo.sh: the Debian packages tbs needs, installed when
# missing. Source it, then call `tbs_install_deps [extra packages...]`.
# libopenblas0-serial: CHOLMOD's supernodal factorization (the fit's control points, region
# faces, LSCM) runs on BLAS; without it Debian's reference BLAS takes half of a region-face
# export. Serial, so that results do not depend on a BLAS thread count.

TBS_PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libtbb-dev nlohmann-json3-dev libcli11-dev libsuitesparse-dev libtinyobjloader-dev
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev libocct-ocaf-dev libocct-visualization-dev
  libtinygltf-dev libstb-dev libopenexr-dev
  libopenblas0-serial
)
TBS_TEST_PACKAGES=(libgtest-dev libgmock-dev libbenchmark-dev python3 python3-jsonschema libcgal-demo
  freecad-python3 clang libclang-rt-14-dev pybind11-dev python3-dev python3-numpy)

tbs_install_deps() {
  local wanted=("${TBS_PACKAGES[@]}" "$@") missing=() p
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -ne 0 ]; then
    echo "tbs: missing Debian packages. Install them with:" >&2
    echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
  echo "tbs: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# Configures (Release) and builds the given targets (all when none) in build/.
tbs_build() {
  local root jobs
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  jobs="$(nproc 2>/dev/null || echo 2)"
  cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  if [ $# -eq 0 ]; then
    cmake --build "$root/build" --parallel "$jobs"
  else
    cmake --build "$root/build" --parallel "$jobs" --target "$@"
  fi
}

# The Khronos glTF validator (npm gltf-validator), for the tests: installed once into
# build/npm (needs npm; Debian's npm package is installed if npm is missing).
tbs_install_gltf_validator() {
  local root dir
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  dir="$root/build/npm"
  [ -f "$dir/node_modules/gltf-validator/package.json" ] && return 0
  if ! command -v npm >/dev/null 2>&1; then
    tbs_install_deps npm
  fi
  mkdir -p "$dir"
  (cd "$dir" && npm install --no-audit --no-fund --loglevel=error gltf-validator@2.0.0-dev.3.10 >/dev/null)
}
