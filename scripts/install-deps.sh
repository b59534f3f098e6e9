#!/usr/bin/env bash
# Installs every Debian package isokit needs to build, test, benchmark and run its demos.
# Idempotent and quick when everything is present (one dpkg-query); uses sudo only when not
# root. The CUDA Toolkit is not a Debian package here: when nvcc is found (PATH or
# /usr/local/cuda) the CUDA backend is built too, otherwise it is skipped.
set -euo pipefail

packages=(
  g++ make cmake pkg-config git           # toolchain (CMake >= 3.25: Debian 12 ships 3.25.1)
  libeigen3-dev                           # dense/sparse linear algebra
  libsuitesparse-dev                      # CHOLMOD (sparse Cholesky)
  libtbb-dev                              # parallel loops
  libopenmesh-dev                         # mesh I/O and topology
  libboost-graph-dev                      # skeleton topology
  libassimp-dev                           # rig loading (glTF scenes, FBX, COLLADA)
  libtinygltf-dev                         # glTF container, JSON and writers
  libcgal-dev                             # exact self-intersection counts (skin metrics)
  libcli11-dev nlohmann-json3-dev         # command lines, JSON
  libcairo2-dev                           # 2D figures (PNG/SVG/PDF)
  libglfw3-dev libimgui-dev               # interactive GUIs
  xvfb xauth libgl1-mesa-dri              # headless GUI tests (xvfb-run, Mesa software GL)
  catch2 libbenchmark-dev                 # tests, benchmarks
  python3-dev pybind11-dev                # the Python module (docs/python.md)
  python3-numpy python3-pytest python3-matplotlib  # its arrays, tests and docs examples
  python3-distributed                     # isokit-batch on a Dask cluster (docs/batch.md)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null | grep -qx installed || missing+=("$p")
done

# The Khronos glTF validator (npm, not a Debian package), run by a test when node is present;
# optional: skipped without npm or without a network.
install_validator() {
  command -v npm >/dev/null || return 0
  [ -d "$(npm root -g)/gltf-validator" ] && return 0
  echo "install-deps: npm install -g gltf-validator"
  npm install -g gltf-validator >/dev/null 2>&1 || echo "install-deps: gltf-validator not installed (optional)"
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  install_validator
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
install_validator
