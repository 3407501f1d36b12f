#!/usr/bin/env bash
# Installs the Debian packages linespace needs (only those missing) and builds it in Release.
# Used by the README's two commands; safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake ninja-build pkg-config ccache
  libtbb-dev libxsimd-dev libglm-dev libopenexr-dev libpng-dev
  glslang-dev glslang-tools spirv-tools catch2 libtinygltf-dev libembree-dev nlohmann-json3-dev libcli11-dev
  mesa-vulkan-drivers libvulkan-dev vulkan-tools
  libglvnd0 libglx0 libegl1 libx11-6 libxext6  # carried by the GPU bundle for a GPU driver (scripts/make-gpu-bundle.sh)
  python3-matplotlib   # linespace-validate sweep plots (validate/plot_tradeoff.py)
  valgrind             # scripts/profile-callgrind.sh (instructions a ray, docs/performance.md)
  python3 sweethome3d-furniture libcgal-demo  # the real scenes: assembler, sources (scenes/README.md)
  clang-14 libclang-rt-14-dev)  # clang-14 + its runtimes: the libFuzzer harnesses (scripts/run-sanitizers.sh)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

cmake --preset release >/dev/null
cmake --build --preset release
