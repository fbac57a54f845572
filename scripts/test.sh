#!/usr/bin/env bash
# Installs dependencies, builds from scratch and runs the whole test suite (ctest).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
export SHIMMER_BUILD_DIR="${SHIMMER_BUILD_DIR:-$root/build}"
rm -rf "$SHIMMER_BUILD_DIR"
# Warnings are errors here, so that the build stays warning-free.
bash "$root/scripts/build.sh" -DSHIMMER_BUILD_TESTS=ON -DSHIMMER_BUILD_BENCH=ON -DSHIMMER_WERROR=ON
# lavapipe and the Vulkan loader want a runtime dir when none is set (headless machines).
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cd "$SHIMMER_BUILD_DIR"
ctest --output-on-failure -j "$(nproc)" "$@"
