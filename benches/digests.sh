#!/usr/bin/env bash
# Byte-identity check for refactors: prints one "sha256  name" line per output
# (SVG, PNG, layout JSON, HTML) for every shipped example, every paper dataset
# and a 1,000-leaf generated similarity hierarchy. Run it at two revisions and
# diff the listings: a refactor that changes no output byte gives none.
#
#   bash benches/digests.sh [BINARY] > before.txt
#
# BINARY defaults to target/release/nptreemap (built if missing). Needs
# python3 and the paper's data (tests/data/paper, or ../shared/paper-data).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/nptreemap}
[ -x "$bin" ] || cargo build --release --quiet
bin=$(realpath "$bin")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Every example, through the config (build).
cp -r examples "$work/examples"
rm -rf "$work/examples/out"
"$bin" build --cold "$work/examples/nptreemap.yaml" >/dev/null
for f in "$work"/examples/*/nptreemap.yaml; do
  rm -rf "$(dirname "$f")/out"
  "$bin" build --cold "$f" >/dev/null
done

# Every paper dataset and the generated hierarchy, through `layout`.
paper=tests/data/paper
[ -d "$paper" ] || paper=../shared/paper-data
mkdir -p "$work/single"
python3 benches/gen_similar.py --n 1000 --depth 3 --dim 16 --seed 1 --out "$work/gen1000.json" >/dev/null
for input in "$paper"/*.json "$work/gen1000.json"; do
  name=$(basename "$input" .json)
  "$bin" layout "$input" --out "$work/single/$name.svg" --out "$work/single/$name.png" \
    --out "$work/single/$name.json" --out "$work/single/$name.html"
done
(cd "$work" && find . -type f \( -name '*.svg' -o -name '*.png' -o -name '*.json' -o -name '*.html' \) \
  ! -path './examples/data/*' ! -path '*/.nptreemap/*' ! -name 'gen1000.json' -print0 \
  | sort -z | xargs -0 sha256sum)
