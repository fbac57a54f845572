#!/usr/bin/env bash
# Regenerates the committed reports under results/ with the built shimmer:
# runs every spec into runs/<spec>/ (a store and its frame cache, kept, so a
# second call recomputes only the jobs whose ids moved) and writes each
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

run() {  # run SPEC: the spec's jobs into runs/SPEC
  local spec=$1
  echo "== $spec: $(date -u +%H:%M:%S)"
  "$shimmer" run "experiments/specs/$spec.json" --jobs 2 --db "runs/$spec/results.db" --work "runs/$spec/frames"
}

for spec in "${specs[@]}"; do
  case "$spec" in
    standard)
      run standard
      "$shimmer" report runs/standard/results.db -o results/standard --title "shimmer standard spec" \
        --fits results/engine-settings/fit.json ;;
    quick)
      run quick
      "$shimmer" report runs/quick/results.db -o results/quick --title "shimmer quick spec" ;;
    normal-maps)
      run normal-maps
      "$shimmer" report runs/normal-maps/results.db -o results/normal-maps --title "shimmer normal-map filters" ;;
    glints)
      run glints
      "$shimmer" report runs/glints/results.db -o results/glints --title "shimmer glints" ;;
    engine-settings)
      run engine-settings
      "$shimmer" report runs/engine-settings/results.db -o results/engine-settings --title "shimmer engine settings" ;;
    user-variants)
      run user-variants
      "$shimmer" report runs/user-variants/results.db -o results/user-variants ;;
    external)
      # The "engine's" frames: tk19 and a reference rendered by shimmer as if
      # an engine had written them (experiments/specs/external.json).
      frames=(--scene sphere-field --material ggx:0.02 --camera orbit --size 64 64 --frames 24)
      [ -d runs/external-frames/tk19 ] ||
        "$shimmer" render "${frames[@]}" --variant tk19 --out runs/external-frames/tk19
      [ -d runs/external-frames/reference ] ||
        "$shimmer" render "${frames[@]}" --reference-spp 16 --out runs/external-frames/reference
      run external
      "$shimmer" report runs/external/results.db -o results/external --video --slow 2 \
        --title "shimmer: an engine's frames beside shimmer's variants" ;;
    *)
      echo "regenerate-results: unknown spec '$spec'" >&2
      exit 2 ;;
  esac
done
echo "== done: $(date -u +%H:%M:%S)"
