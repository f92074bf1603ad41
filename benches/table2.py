#!/usr/bin/env python3
"""Reproduces the paper's Table 2 comparison and times the whole method.

For every Table 2 dataset in tests/data/paper (../shared/paper-data when that is
absent), runs
`nptreemap eval FILE --method M --seed S --json` for every method and seeds 1-5
and prints the median realised leaf constraints per method next to the paper's
figures; then times `nptreemap bench` (prepare + constraints + layout, parsing
excluded) on flare and on two generated hierarchies with embeddings
(benches/gen_similar.py). Prints Markdown for BENCHMARKS.md.

usage: python3 benches/table2.py [--bin target/release/nptreemap] [--no-build]
"""
import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# The paper's data: the repository's copy, else the shared folder beside it.
PAPER = REPO / "tests" / "data" / "paper"
if not PAPER.is_dir():
    PAPER = REPO / ".." / "shared" / "paper-data"
METHODS = ["plain", "random-cvt", "proj-scale", "match-swap", "neighbor"]
# file, label, leaf constraints, paper: random CVT / proj+scale / match+swap / optimised
TABLE2 = [
    ("country_pop_50M_AUS.json", "Country Pop.", 18, (5, 11, 15, 15)),
    ("cifar10.json", "Cifar-10", 19, (9, 10, 14, 14)),
    ("flare.json", "Flare", 547, (147, 151, 223, 220)),
    ("imdb_100_genre_sim_2child.json", "IMDB Genres", 42, (16, 14, 30, 29)),
    ("syntheticPoints_10nodes_2components.json", "Synthetic m-n", 11, (4, 4, 10, 9)),
    ("2_level_4_cousin_constraints.json", "Synthetic 2 lvl", 24, (18, 17, 19, 19)),
]


def run_json(cmd):
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=str(REPO / "target" / "release" / "nptreemap"))
    ap.add_argument("--no-build", action="store_true")
    args = ap.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=REPO, check=True, stdout=sys.stderr)
    nb = args.bin
    print(f"- Date (UTC): {dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M}")
    print(f"- Machine: {os.cpu_count()} CPUs; command: `python3 benches/table2.py`\n")
    print("Realised leaf constraints, median over seeds 1-5 (each layout's area error "
          "≤ 0.01, checked by tests/tools/check_layout.py in the tests):\n")
    print("| dataset | constraints | " + " | ".join(METHODS) + " | paper rand. CVT / proj.+scale / match+swap / optimised |")
    print("|---|---:|" + "---:|" * len(METHODS) + "---|")
    for file, label, n, paper in TABLE2:
        path = PAPER / file
        cells = []
        for m in METHODS:
            counts = [run_json([nb, "eval", str(path), "--json", "--method", m, "--seed", str(s)])["realized"]
                      for s in range(1, 6)]
            cells.append(f"{statistics.median(counts):g}")
        print(f"| {label} | {n} | " + " | ".join(cells) + f" | {' / '.join(map(str, paper))} |")
    bench_dir = REPO / "target" / "bench"
    bench_dir.mkdir(parents=True, exist_ok=True)
    gen = REPO / "benches" / "gen_similar.py"
    cases = [("flare (paper data)", PAPER / "flare.json", None)]
    for n, depth in ((429, 5), (5000, 3)):
        out = bench_dir / f"sim{n}_d{depth}.json"
        if not out.exists():
            subprocess.run([sys.executable, str(gen), "--n", str(n), "--depth", str(depth), "--dim", "64",
                            "--seed", "1", "--out", str(out)], check=True)
        cases.append((f"{n} leaves, {depth + 1} levels, 64-d", out, None))
    print("\nWhole method (`nptreemap bench FILE --repeat 3`: prepare, constraints, layout; median):\n")
    print("| input | nodes | constraints (all levels) | realised | time (ms) |")
    print("|---|---:|---:|---:|---:|")
    for label, path, _ in cases:
        r = run_json([nb, "bench", str(path), "--repeat", "3"])
        print(f"| {label} | {r['leaves']} leaves | {r['constraints']} | {r['realized']} | {r['time_ms']:.0f} |")


if __name__ == "__main__":
    main()
