#!/usr/bin/env bash
# The speed figures the guide shows (docs/guide.md, "Speed"), measured, not
# copied: runs the shading, renderer and metrics benchmarks (Google
# Benchmark, JSON out) and writes results/speed/report.md, every ratio
# measured side by side in one run of one binary, with the aims of the
# performance work beside what this machine reached. Then fills the docs'
# generated blocks (scripts/readme-tour.sh --blocks-only).
#   bash scripts/speed-report.sh [PART...]   (after bash scripts/build.sh -DSHIMMER_BUILD_BENCH=ON)
# PART: shading, renderer, metrics, bvh, mesh (default: all). A part left
# out keeps its JSON of an earlier run; the report says which run each comes
# from only through its JSON's date, and every ratio stays within one part.
# The numpy/scipy baseline of the metrics bench needs Debian's python3-numpy
# and python3-scipy under /usr/bin/python3 (SHIMMER_PYTHON overrides); without
# them its row says so.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
bench="${SHIMMER_BUILD_DIR:-$root/build}/bench"
out="$root/results/speed"
parts=("$@")
[ ${#parts[@]} -eq 0 ] && parts=(shading renderer metrics bvh mesh)
wants() { local p; for p in "${parts[@]}"; do [ "$p" = "$1" ] && return 0; done; return 1; }
for b in shading_bench renderer_bench metrics_bench triangle_bvh_bench; do
  [ -x "$bench/$b" ] || { echo "speed-report: error: no $bench/$b (configure with -DSHIMMER_BUILD_BENCH=ON and build)" >&2; exit 2; }
done
# The benchmarks' own JSON is kept beside the report (results/speed/*.json):
# the report can be made again from it (scripts/speed_report.py DIR OUT).
work="$out/json"
mkdir -p "$work"
export SHIMMER_PYTHON="${SHIMMER_PYTHON:-/usr/bin/python3}"
run() {  # NAME BINARY ARGS...: JSON into $work/NAME.json, progress on stderr
  local name=$1 binary=$2
  shift 2
  echo "speed-report: $name $(date -u +%H:%M:%S)" >&2
  "$bench/$binary" --benchmark_format=json --benchmark_out="$work/$name.json.tmp" --benchmark_out_format=json "$@" \
    >/dev/null
  mv "$work/$name.json.tmp" "$work/$name.json"
}
wants shading && run shading shading_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
wants renderer && run renderer renderer_bench --benchmark_repetitions=3 --benchmark_enable_random_interleaving=true \
  --benchmark_report_aggregates_only=true
wants metrics && run metrics metrics_bench
wants bvh && run bvh triangle_bvh_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
if wants mesh; then
  # `none` and the reference on a 102,400-triangle torus (scripts/generate-assets.py --bench), the
  # reference at 4x4 samples a replicate: a mesh sample costs several times an analytic one.
  assets=$(mktemp -d)
  python3 "$root/scripts/generate-assets.py" --bench "$assets"
  SHIMMER_BENCH_SCENE="$assets/torus-100k.json" SHIMMER_BENCH_REFERENCE_SPP=4 run mesh renderer_bench \
    --benchmark_filter='^(frame/none/quad|reference)' --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
  rm -rf "$assets"
fi
python3 "$root/scripts/speed_report.py" "$work" "$out/report.md.tmp"
mv "$out/report.md.tmp" "$out/report.md"
echo "speed-report: $out/report.md" >&2
bash "$root/scripts/readme-tour.sh" --blocks-only
