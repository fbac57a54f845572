#!/usr/bin/env bash
# Installs every Debian 12 package shimmer needs to build, test and run.
# Idempotent: when everything is present it only checks and returns.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libvulkan-dev mesa-vulkan-drivers vulkan-tools vulkan-validationlayers
  glslang-dev glslang-tools spirv-tools
  libopencv-dev libopenexr-dev openexr libdeflate-dev
  libceres-dev libeigen3-dev
  libcli11-dev nlohmann-json3-dev libsqlite3-dev libglm-dev
  libtinygltf-dev libtinyobjloader-dev
  libgtest-dev libgmock-dev libbenchmark-dev libtbb-dev
  gnuplot-nox chromium
  slurm-wlm munge sqlite3 python3
  python3-numpy python3-scipy  # the metrics benchmark's baseline (bench/metrics_numpy_baseline.py)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
