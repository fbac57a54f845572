#!/usr/bin/env bash
# The speed figures the guide shows (docs/guide.md, "Speed"), measured, not
# copied: runs the shading, renderer and metrics benchmarks (Google
# Benchmark, JSON out) and writes results/speed/report.md, every ratio
# measured side by side in one run of one binary, with the aims of the
# performance work beside what this machine reached. Then fills the docs'
# generated blocks (scripts/readme-tour.sh --blocks-only).
#   bash scripts/speed-report.sh        (after bash scripts/build.sh -DSHIMMER_BUILD_BENCH=ON)
# The numpy/scipy baseline of the metrics bench needs Debian's python3-numpy
# and python3-scipy under /usr/bin/python3 (SHIMMER_PYTHON overrides); without
# them its row says so.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
bench="${SHIMMER_BUILD_DIR:-$root/build}/bench"
out="$root/results/speed"
for b in shading_bench renderer_bench metrics_bench; do
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
run shading shading_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
run renderer renderer_bench --benchmark_repetitions=3 --benchmark_enable_random_interleaving=true \
  --benchmark_report_aggregates_only=true
run metrics metrics_bench
python3 "$root/scripts/speed_report.py" "$work" "$out/report.md.tmp"
mv "$out/report.md.tmp" "$out/report.md"
echo "speed-report: $out/report.md" >&2
bash "$root/scripts/readme-tour.sh" --blocks-only
