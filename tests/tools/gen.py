#!/usr/bin/env python3
# What this file owns: the seeded random hierarchies the integration tests lay out
# (tests/suite/support.rs `generate`). Origin: a verbatim copy of the project's
# shared peer-benchmark harness, shared/peers/gen.py (written for this project, no
# third-party code), kept here so the tests read nothing outside the repository.
# benches/ keep using shared/peers/gen.py beside the d3 peer; keep the two equal.
"""Seeded random hierarchy generator for the Voronoi-treemap peer benchmarks.

Writes a JSON tree {"name": ..., "children": [...]} whose leaves carry a
numeric weight field (default "weight"; internal nodes carry no weight, the
tools sum leaves themselves).  Optionally also writes the same tree in the
"nodeId;parentId;name;weight" edge-list text format read by Nocaj & Brandes'
Java library (IO.readEdgeList), so every tool sees the identical hierarchy.

Shape:
  * exactly N leaves, all at depth D (root = depth 0, leaves = depth D);
  * fan-out: with --branching B every internal node above the last internal
    level has min(B, leaves-below) children and the last internal level
    takes whatever is left (about N / B^(D-1) children each);
    without --branching (default) the fan-out is balanced automatically:
    a node with n leaves below it and d levels to go gets round(n^(1/d))
    children, i.e. about N^(1/D) at every level;
  * leaves are split between siblings by a jittered (Gamma(4)) proportion,
    each child getting at least one leaf, so subtree sizes vary;
  * leaf weights ~ LogNormal(mu, sigma) (defaults 0, 1).

Examples:
  python3 gen.py --n 1000 --depth 3 --seed 1 --out data/h1000.json \
                 --nocaj-out data/h1000.txt
"""
import argparse
import json
import math
import random
import sys


def split_counts(rng, n, k):
    """Split n leaves into k >= 1 positive parts with jittered proportions."""
    if k <= 1:
        return [n]
    props = [rng.gammavariate(4.0, 1.0) for _ in range(k)]
    s = sum(props)
    rest = n - k  # every part gets 1, distribute the rest
    raw = [rest * p / s for p in props]
    parts = [int(math.floor(r)) for r in raw]
    left = rest - sum(parts)
    order = sorted(range(k), key=lambda i: raw[i] - parts[i], reverse=True)
    for i in order[:left]:
        parts[i] += 1
    return [p + 1 for p in parts]


def build(args):
    rng = random.Random(args.seed)
    counter = [0]

    def new_name(prefix):
        counter[0] += 1
        return "%s%d" % (prefix, counter[0])

    def make(n, levels_left, is_root=False):
        node = {"name": "root" if is_root else new_name("g")}
        if levels_left == 1:
            node["children"] = [
                {"name": new_name("l"),
                 args.weight_field: round(rng.lognormvariate(args.mu, args.sigma), 6)}
                for _ in range(n)
            ]
            return node
        if args.branching:
            k = min(args.branching, n)
        else:
            k = max(1, min(n, int(round(n ** (1.0 / levels_left)))))
        node["children"] = [make(c, levels_left - 1) for c in split_counts(rng, n, k)]
        return node

    if args.depth < 1:
        sys.exit("depth must be >= 1")
    return make(args.n, args.depth, is_root=True)


def write_nocaj(tree, path, weight_field):
    """nodeId;parentId;name;weight edge list (root appears only as a parent)."""
    lines = ["nodeId;parentId;name;weight"]

    def total(node):
        if "children" in node:
            return sum(total(c) for c in node["children"])
        return node[weight_field]

    def walk(node):
        for c in node.get("children", []):
            lines.append("%s;%s;%s;%r" % (c["name"], node["name"], c["name"], float(total(c))))
            walk(c)

    walk(tree)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def stats(tree):
    leaves, internal, depths = 0, 0, set()
    fan = []

    def walk(node, d):
        nonlocal leaves, internal
        ch = node.get("children")
        if ch:
            internal += 1
            fan.append(len(ch))
            for c in ch:
                walk(c, d + 1)
        else:
            leaves += 1
            depths.add(d)

    walk(tree, 0)
    return {"leaves": leaves, "internal": internal, "leaf_depths": sorted(depths),
            "fanout_min": min(fan), "fanout_max": max(fan),
            "fanout_mean": round(sum(fan) / len(fan), 2)}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, required=True, help="number of leaves")
    ap.add_argument("--depth", type=int, default=3, help="leaf depth D (root=0)")
    ap.add_argument("--branching", type=int, default=0,
                    help="fan-out B of the upper levels (0 = balanced N^(1/D))")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mu", type=float, default=0.0, help="lognormal mu")
    ap.add_argument("--sigma", type=float, default=1.0, help="lognormal sigma")
    ap.add_argument("--weight-field", default="weight")
    ap.add_argument("--out", required=True, help="JSON output path")
    ap.add_argument("--nocaj-out", help="also write Nocaj edge-list text here")
    args = ap.parse_args()

    tree = build(args)
    with open(args.out, "w") as f:
        json.dump(tree, f, separators=(",", ":"))
    if args.nocaj_out:
        write_nocaj(tree, args.nocaj_out, args.weight_field)
    print(json.dumps(stats(tree)), file=sys.stderr)


if __name__ == "__main__":
    main()
