#!/usr/bin/env bash
# The main job: installs dependencies, builds shimmer and runs it.
# For now: lists the filter variants and evaluates filtered NDFs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh" -DSHIMMER_BUILD_TESTS=OFF -DSHIMMER_BUILD_BENCH=OFF
shimmer="${SHIMMER_BUILD_DIR:-$root/build}/experiments/shimmer"
"$shimmer" variants
echo "--- a 0.01-roughness GGX lobe seen through a 0.05 x 0.02 slope-space footprint:"
for v in none k16-ggx-rect k16-ggx-rect-stable k16-beckmann-rect tk19; do
  "$shimmer" ndf --variant "$v" --ndf ggx --alpha 0.01 --slope 0.03 0.0 --footprint 0.05 0.02 --json
done
