#!/usr/bin/env bash
# What a `shimmer render` pays before its first frame, cold and warm, side by
# side in one run: each round renders the same short sequence three ways,
#   cold   a fresh, empty $XDG_CACHE_HOME (no shimmer kernel cache, and no
#          Mesa shader cache either: a machine's first render),
#   warm   the same $XDG_CACHE_HOME again (the second render of a variant),
#   off    SHIMMER_CACHE=off with Mesa's cache warm (only shimmer's cache
#          missing: what the disk cache itself saves),
# and prints the medians over rounds of the renderer's own start-up timings
# (sequence.json's timings_ms) and of the process's wall time.
#
#   bench/startup_bench.sh [ROUNDS=5] [shimmer render options...]
#   e.g. bench/startup_bench.sh 5 --variant k16-ggx-rect --scene wires
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
shimmer="${SHIMMER:-$root/build/experiments/shimmer}"
rounds=${1:-5}
shift || true
[[ -x "$shimmer" ]] || { echo "startup_bench: error: no $shimmer (build first)" >&2; exit 2; }
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

render() {  # render MODE CACHE_HOME ROUND [shimmer render options...]
  local out="$scratch/out-$1-$3" start end cache=on
  [[ $1 == off ]] && cache=off
  start=$(date +%s%N)
  SHIMMER_CACHE=$cache XDG_CACHE_HOME="$2" "$shimmer" render --variant tk21 --frames 2 --size 64 64 "${@:4}" \
    --out "$out" >/dev/null
  end=$(date +%s%N)
  echo "$1 $(( (end - start) / 1000000 )) $out/sequence.json" >>"$scratch/runs"
}

for ((r = 0; r < rounds; ++r)); do
  cache="$scratch/cache-$r"
  render cold "$cache" "$r" "$@"
  render warm "$cache" "$r" "$@"
  render off "$cache" "$r" "$@"
done

python3 - "$scratch/runs" <<'EOF'
import json, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    mode, wall, sequence = line.split()
    t = json.load(open(sequence))["timings_ms"]
    rows.setdefault(mode, []).append(dict(t, process_wall=float(wall)))
keys = ["startup", "shader_compile", "specialize", "pipeline_create", "first_dispatch_jit", "process_wall"]
print("medians in ms over %d rounds" % len(rows["cold"]))
print("%-6s" % "" + "".join("%20s" % k for k in keys))
median = {m: {k: statistics.median(r[k] for r in runs) for k in keys} for m, runs in rows.items()}
for mode in ["cold", "warm", "off"]:
    print("%-6s" % mode + "".join("%20.1f" % median[mode][k] for k in keys))
first = lambda m: median[m]["startup"] + median[m]["first_dispatch_jit"]
print("to the first frame (startup + first dispatch): cold %.0f ms, warm %.0f ms (%.1fx sooner), "
      "cache off %.0f ms (%.1fx)" % (first("cold"), first("warm"), first("cold") / first("warm"),
                                     first("off"), first("off") / first("warm")))
EOF
