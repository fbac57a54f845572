#!/usr/bin/env bash
# The README's five-minute tour, run for real: renders a shot and its
# reference, measures them, and writes each command with its output to
# results/tour/*.txt; then puts those files, and the standard report's answer
# grid, into the README's generated blocks (tests/experiments/readme_test.cpp
# checks that they match). Run after `bash scripts/build.sh`.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
bin="${SHIMMER_BUILD_DIR:-$root/build}/experiments"
out="$root/results/tour"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
cd "$work"
# Each step: the command as a user types it, then what it printed.
step() {
  local file=$1
  shift
  { echo "\$ $*"; PATH="$bin:$PATH" "$@" 2>&1; } >"$out/$file.tmp"
  mv "$out/$file.tmp" "$out/$file"
}
step render.txt shimmer render --scene sphere-field --camera orbit --variant none --frames 16 --size 96 96 --out demo
step render-reference.txt shimmer render --scene sphere-field --camera orbit --variant none --frames 16 --size 96 96 \
  --reference-spp 4 --out demo-ref
step render-filter.txt shimmer render --scene sphere-field --camera orbit --variant tk21 --frames 16 --size 96 96 \
  --out demo-tk21
step metrics.txt shimmer metrics demo demo-ref --highlight-mask --highlight-threshold 0.1
step metrics-filter.txt shimmer metrics demo-tk21 demo-ref --highlight-mask --highlight-threshold 0.1
cd "$root"
python3 - "$root/README.md" <<'PY'
import re, sys, pathlib
readme = pathlib.Path(sys.argv[1])
root = readme.parent
def content(source):
    path, _, part = source.partition("#")
    text = (root / path).read_text()
    if part == "answer":  # the grid: the first table after "## Answer"
        lines = text[text.index("\n## Answer\n"):].splitlines()
        first = next(i for i, l in enumerate(lines) if l.startswith("|"))
        end = next(i for i in range(first, len(lines)) if not lines[i].startswith("|"))
        return "\n".join(lines[first:end]) + "\n"
    return "```console\n" + text + "```\n"
pattern = re.compile(r"(<!-- generated from (\S+) -->\n)(.*?)(<!-- end generated -->)", re.S)
readme.write_text(pattern.sub(lambda m: m.group(1) + content(m.group(2)) + m.group(4), readme.read_text()))
PY
echo "tour: $out; README blocks updated"
