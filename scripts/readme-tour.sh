#!/usr/bin/env bash
# The README's five-minute tour, run for real: renders a shot and its
# reference, measures them, and writes each command with its output to
# results/tour/*.txt; then puts those files, and the reports' tables they
# name, into the generated blocks of the README and docs/*.md
# (tests/experiments/readme_test.cpp checks that they match). Run after
# `bash scripts/build.sh`. With --blocks-only it renders nothing and only
# fills the blocks again from the files as they are (after a report moved).
set -euo pipefail
blocks_only=false
[ "${1:-}" = --blocks-only ] && blocks_only=true
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
if ! $blocks_only; then
step render.txt shimmer render --scene sphere-field --camera orbit --variant none --frames 16 --size 96 96 --out demo
step render-reference.txt shimmer render --scene sphere-field --camera orbit --variant none --frames 16 --size 96 96 \
  --reference-spp 4 --out demo-ref
step render-filter.txt shimmer render --scene sphere-field --camera orbit --variant tk21 --frames 16 --size 96 96 \
  --out demo-tk21
step metrics.txt shimmer metrics demo demo-ref --highlight-mask --highlight-threshold 0.1
step metrics-filter.txt shimmer metrics demo-tk21 demo-ref --highlight-mask --highlight-threshold 0.1
step sweep.txt shimmer sweep --scene sphere --material ggx:0.01 --variant k16-beckmann-rect \
  --param fp_max=0.01:1:4 --log --size 48 48 --frames 8
# The guide's filter math (docs/guide.md, section 1): one filter evaluated directly.
step ndf.txt shimmer ndf --variant k16-beckmann-rect --alpha 0.01 --slope 0.03 0 --footprint 0.05 0.02 --json
step ndf-rect-float.txt shimmer ndf --variant k16-ggx-rect --param fp_min_cap=0 --alpha 0.01 --slope 0.05 0 \
  --footprint 1e-6 1e-6 --precision float
step ndf-rect-stable-float.txt shimmer ndf --variant k16-ggx-rect-stable --alpha 0.01 --slope 0.05 0 \
  --footprint 1e-6 1e-6 --precision float
step ndf-rect-stable-double.txt shimmer ndf --variant k16-ggx-rect-stable --alpha 0.01 --slope 0.05 0 \
  --footprint 1e-6 1e-6 --precision double
step ndf-centre-jacobian.txt shimmer ndf --variant k16-ggx-rect-stable --alpha 0.2 --slope 2 0 --footprint 1 1 \
  --precision float
step ndf-inner-jacobian.txt shimmer ndf --variant k16-ggx-rect-jacobian --alpha 0.2 --slope 2 0 --footprint 1 1 \
  --precision float
# A mesh asset (the low-poly torus of experiments/scenes): its first frame and
# the map of its error's flicker go to docs/images for the README.
cp "$root/experiments/scenes/torus-lowpoly.gltf" "$root/experiments/scenes/torus-lowpoly.bin" .
step render-asset.txt shimmer render --asset torus-lowpoly.gltf --material ggx:0.05 --camera orbit --frames 16 \
  --size 128 128 --out torus --preview torus.png
step render-asset-reference.txt shimmer render --asset torus-lowpoly.gltf --material ggx:0.05 --camera orbit \
  --frames 16 --size 128 128 --reference-spp 4 --out torus-ref
step metrics-asset.txt shimmer metrics torus torus-ref --highlight-mask --highlight-threshold 0.1 --out torus-maps
cp torus.png "$root/docs/images/asset-torus-lowpoly-none.png"
cp torus-maps/tv_err.png "$root/docs/images/asset-torus-lowpoly-tv_err.png"
# The README's glint strip (docs/glints.md): frame 0 of glint-plane under
# orbit, the reference beside seed 001's model as published, its counted
# form, Deliot and Belcour's anisotropic grids and shimmer's point microdetails.
glint=(--scene glint-plane --material glints:0.3,local=0.03,density=1e4 --camera orbit --frames 1 --size 128 128)
PATH="$bin:$PATH" shimmer render "${glint[@]}" --reference-spp 8 --out glint-ref \
  --preview "$root/docs/images/glints-reference.png" >/dev/null
for v in glints-zk16 glints-zk16-counting glints-db23 glints-points; do
  PATH="$bin:$PATH" shimmer render "${glint[@]}" --variant "$v" --out "glint-$v" --preview "$root/docs/images/$v.png" \
    >/dev/null
done
fi
cd "$root"
# The generated blocks of the README and of docs/*.md: a console transcript
# (a file), a report's answer grid (REPORT#answer), or the first table after
# one of a report's headings (REPORT#table:ANCHOR, the heading's anchor).
python3 - "$root/README.md" "$root"/docs/*.md <<'PY'
import re, sys, pathlib
def anchor(heading):  # GitHub's, as report_document.cpp's Anchor
    return "".join(c.lower() if (ord(c) >= 0x80 or c.isalnum() or c in "-_") else "-" if c == " " else ""
                   for c in heading)
def first_table(lines, start):
    first = next(i for i in range(start, len(lines)) if lines[i].startswith("|"))
    end = next((i for i in range(first, len(lines)) if not lines[i].startswith("|")), len(lines))
    return "\n".join(lines[first:end]) + "\n"
def content(root, source):
    path, _, part = source.partition("#")
    text = (root / path).read_text()
    lines = text.splitlines()
    if part == "answer":  # the grid: the first table after "## Answer"
        return first_table(lines, lines.index("## Answer"))
    if part.startswith("table:"):
        want = part[len("table:"):]
        at = next(i for i, l in enumerate(lines) if l.startswith("#") and anchor(l.lstrip("#").strip()) == want)
        return first_table(lines, at + 1)
    return "```console\n" + text + "```\n"
pattern = re.compile(r"(<!-- generated from (\S+) -->\n)(.*?)(<!-- end generated -->)", re.S)
root = pathlib.Path(sys.argv[1]).parent
def fill(m):
    if not (root / m.group(2).partition("#")[0]).exists():  # not made yet: the block stays as it is
        print(f"readme-tour: warning: no {m.group(2)}; its block is left as it was", file=sys.stderr)
        return m.group(0)
    return m.group(1) + content(root, m.group(2)) + m.group(4)
for name in sys.argv[1:]:
    page = pathlib.Path(name)
    page.write_text(pattern.sub(fill, page.read_text()))
PY
echo "tour: $out; README and docs blocks updated"
