#!/usr/bin/env python3
"""A flat set of leaves with clustered embeddings (issue 34 item 4): `--clusters`
Gaussian clusters of unit-norm centres in `--dim` dimensions, each leaf its
cluster's centre plus noise of `--spread` per dimension (digits-like: 64-d, 10
clusters; sentence-like: 384-d, 100 clusters), lognormal weights. Cosine
similarity. Seeded; standard library only.

    python3 benches/gen_clustered.py --n 10000 --dim 64 --clusters 10 --out FILE.json
"""
import argparse
import json
import math
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, required=True)
    ap.add_argument("--dim", type=int, default=64)
    ap.add_argument("--clusters", type=int, default=10)
    ap.add_argument("--spread", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    centres = []
    for _ in range(args.clusters):
        c = [rng.gauss(0, 1) for _ in range(args.dim)]
        norm = math.sqrt(sum(x * x for x in c))
        centres.append([x / norm for x in c])
    leaves = []
    for i in range(args.n):
        c = centres[rng.randrange(args.clusters)]
        v = [round(x + rng.gauss(0, args.spread), 5) for x in c]
        leaves.append({"id": f"n{i}", "name": f"n{i}", "weight": round(rng.lognormvariate(0, 1), 4),
                       "embeddings": v})
    doc = {"id": "root", "name": "root", "similarityMeasure": "cosine",
           "weightAttribute": "weight", "children": leaves}
    with open(args.out, "w") as f:
        json.dump(doc, f, separators=(",", ":"))


if __name__ == "__main__":
    main()
