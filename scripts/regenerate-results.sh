#!/usr/bin/env bash
# Regenerates the committed reports under results/ with the built shimmer:
# runs every spec into runs/<spec>/ (a store, kept, so a
# second call recomputes only the jobs whose ids moved; the frames are
# deleted once measured, so a metrics-only change renders again: `run
# --keep-frames` would keep them, at about 30 MB a job) and writes each
# report into results/<spec>/, then the README tour. The fits (fit.json,
# fit.md) are not re-run here: `shimmer fit` takes them (docs/guide.md).
# Usage: scripts/regenerate-results.sh [SPEC ...]   (default: every spec)
# Run after `bash scripts/build.sh`; SHIMMER_BIN overrides the binary.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
shimmer="${SHIMMER_BIN:-${SHIMMER_BUILD_DIR:-$root/build}/experiments/shimmer}"
cd "$root"
specs=("$@")
[ ${#specs[@]} -gt 0 ] || specs=(standard quick normal-maps glints engine-settings user-variants external)

# Each spec's report title (and report options).
declare -A title=(
  [standard]="shimmer standard spec" [quick]="shimmer quick spec" [normal-maps]="shimmer normal-map filters"
  [glints]="shimmer glints" [engine-settings]="shimmer engine settings" [user-variants]="shimmer report"
  [external]="shimmer: an engine's frames beside shimmer's variants")
declare -A options=([standard]="--fits results/engine-settings/fit.json" [external]="--video --slow 2")

for spec in "${specs[@]}"; do
  if [ -z "${title[$spec]+set}" ]; then
    echo "regenerate-results: unknown spec '$spec' (the specs: ${!title[*]})" >&2
    exit 2
  fi
  echo "== $spec: $(date -u +%H:%M:%S)"
  if [ "$spec" = external ]; then
    # The "engine's" frames: tk19 and a reference rendered by shimmer as if
    # an engine had written them (experiments/specs/external.json).
    frames=(--scene sphere-field --material ggx:0.02 --camera orbit --size 64 64 --frames 24)
    [ -d runs/external-frames/tk19 ] ||
      "$shimmer" render "${frames[@]}" --variant tk19 --out runs/external-frames/tk19
    [ -d runs/external-frames/reference ] ||
      "$shimmer" render "${frames[@]}" --reference-spp 16 --out runs/external-frames/reference
  fi
  "$shimmer" run "experiments/specs/$spec.json" --jobs 2 --db "runs/$spec/results.db" --work "runs/$spec/frames"
  # shellcheck disable=SC2086 # the options are words
  "$shimmer" report "runs/$spec/results.db" -o "results/$spec" --title "${title[$spec]}" ${options[$spec]:-}
done
# The README's and the docs' generated blocks follow the reports.
echo "== tour: $(date -u +%H:%M:%S)"
SHIMMER_BUILD_DIR="$(dirname "$(dirname "$shimmer")")" bash "$root/scripts/readme-tour.sh"
echo "== done: $(date -u +%H:%M:%S)"
