#!/usr/bin/env python3
"""Seeded random hierarchies with embeddings, for the neighbourhood benchmarks.

Builds the tree with gen.py's shape rules (N leaves at depth D, balanced fan-out,
lognormal weights; tests/tools/gen.py, else ../shared/peers/gen.py, of which it is
a copy), then gives every leaf a D-level random walk embedding: each node's
vector is its parent's plus Gaussian noise, so siblings and cousins are more
similar than strangers, as in real taxonomies.

usage: gen_similar.py --n 5000 --depth 4 --dim 64 --seed 1 --out FILE.json
"""
import argparse
import json
import random
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
GEN = REPO / "tests" / "tools" / "gen.py"
if not GEN.is_file():
    GEN = REPO / ".." / "shared" / "peers" / "gen.py"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, required=True)
    ap.add_argument("--depth", type=int, default=4)
    ap.add_argument("--dim", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--noise", type=float, default=1.0, help="noise per level")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        shape = Path(tmp) / "shape.json"
        subprocess.run([sys.executable, str(GEN), "--n", str(args.n),
                        "--depth", str(args.depth), "--seed", str(args.seed), "--out", str(shape)],
                       check=True, stderr=subprocess.DEVNULL)
        tree = json.loads(shape.read_text())
    rng = random.Random(args.seed * 7919 + 1)

    def walk(node, vec):
        node["id"] = node.pop("name")
        kids = node.get("children")
        if not kids:
            node["embeddings"] = [round(v, 5) for v in vec]
            return
        for k in kids:
            walk(k, [v + rng.gauss(0.0, args.noise) for v in vec])

    walk(tree, [0.0] * args.dim)
    tree["weightAttribute"] = "weight"
    tree["similarityMeasure"] = "cosine"
    Path(args.out).write_text(json.dumps(tree, separators=(",", ":")))


if __name__ == "__main__":
    main()
