#!/bin/sh
# Issue 21, item 8 (issue 23, item 3): a flat border list of N rows (default
# 100,000) without pairs, laid out by `--method neighbor` and `--method plain`
# with the release binary; prints each run's `/usr/bin/time -v` wall clock,
# user time and peak RSS. Nothing to preserve: neighbor should cost what plain
# does (the suite's battery checks the layouts are the same bytes at 10,000).
# Usage (from the repository root): sh benches/border_no_pairs.sh [N]
set -eu
n=${1:-100000}
cargo build --release --quiet
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$n" "$dir" <<'PY'
import sys
n, d = int(sys.argv[1]), sys.argv[2]
with open(f"{d}/nodes.csv", "w") as f:
    f.write("id,weight\n")
    for i in range(n):
        f.write(f"n{i},{1 + (i * 7) % 13}\n")
open(f"{d}/pairs.csv", "w").write("a,b\n")
open(f"{d}/nptreemap.yaml", "w").write(
    "datasets:\n  - name: flat\n    format: border-list\n"
    "    files: {nodes: nodes.csv, pairs: pairs.csv}\n"
    "    fields: {id: id, weight: weight}\n    outputs: [out/flat.json]\n")
PY
for method in neighbor plain; do
    /usr/bin/time -v target/release/nptreemap layout --config "$dir/nptreemap.yaml" \
        --method "$method" --out "$dir/$method.json" 2> "$dir/$method.time"
    printf '%s (%s rows): ' "$method" "$n"
    grep -E 'Elapsed|User time|Maximum resident' "$dir/$method.time" \
        | sed 's/^[[:space:]]*//' | tr '\n' ';'
    echo
done
cmp -s "$dir/neighbor.json" "$dir/plain.json" && echo "same layout" || echo "layouts differ"
