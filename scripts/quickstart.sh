#!/usr/bin/env bash
# The main job: installs dependencies, builds shimmer, runs the quick spec
# (every filter variant on two scenes, about half a minute on 2 cores with lavapipe)
# and writes its report to results/quick/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh" -DSHIMMER_BUILD_TESTS=OFF -DSHIMMER_BUILD_BENCH=OFF
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
shimmer="${SHIMMER_BUILD_DIR:-$root/build}/experiments/shimmer"
cd "$root"
"$shimmer" run experiments/specs/quick.json --db runs/quick/results.db --work runs/quick/frames
"$shimmer" report runs/quick/results.db -o results/quick --title "shimmer quick spec"
echo "report: $root/results/quick/report.md"
