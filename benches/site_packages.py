#!/usr/bin/env python3
"""A site-packages-like hierarchy (issue 34): a folder of Python modules, or a generated one.

Real mode walks a folder (for example one made by `pip install --no-deps --target
/tmp/sp sympy numpy pandas scipy matplotlib`) and writes hierarchy JSON: one leaf per
`.py` file, nested in its folders, weighted by its size in bytes (empty files, such as
most `__init__.py`, weigh 0), with the Jaccard similarity of the top-level names it
imports (each leaf carries those names as a list of strings, as benches/c_headers.py
does with included names).

    python3 benches/site_packages.py OUT.json --root /tmp/sp

Generated mode (`--generate`) writes a tree of the same shape without a download:
`--packages` packages of a few subpackages each, one subpackage of `--big` modules
(default 1,826) whose sizes are half zeros and a heavy (Pareto) tail up to about
91 KB, the other modules lognormal with a tenth empty; sets of imported names drawn
from a few clusters per package. Seeded and deterministic.

    python3 benches/site_packages.py OUT.json --generate [--big 1826] [--seed 1]

Prints the leaf count, depth, empty leaves and the largest diagram on stderr.
Standard library only; deterministic for a given tree or seed.
"""

import argparse
import json
import os
import random
import re
import sys

IMPORT = re.compile(rb"^\s*(?:from\s+([A-Za-z_][\w.]*)\s+import|import\s+([A-Za-z_][\w.]*))",
                    re.MULTILINE)
SKIP_DIRS = {"__pycache__"}
# Files larger than this are read only this far for their imports.
READ_CAP = 1 << 20


def modules(root):
    found = []
    for folder, dirs, files in os.walk(root, followlinks=False):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS)
        for name in sorted(files):
            path = os.path.join(folder, name)
            if name.endswith(".py") and os.path.isfile(path) and not os.path.islink(path):
                found.append(os.path.relpath(path, root))
    found.sort()
    return found


def imports_of(path):
    with open(path, "rb") as f:
        text = f.read(READ_CAP)
    names = set()
    for a, b in IMPORT.findall(text):
        name = (a or b).decode("ascii", "replace").split(".")[0]
        if name:
            names.add(name)
    return sorted(names)


def real(root):
    return [(rel, os.path.getsize(os.path.join(root, rel)), imports_of(os.path.join(root, rel)))
            for rel in modules(root)]


def generate(args):
    rng = random.Random(args.seed)
    pool = [f"name{i}" for i in range(600)]
    leaves = []
    big_pkg = rng.randrange(args.packages)
    for p in range(args.packages):
        clusters = [rng.sample(pool, 12) for _ in range(4)]
        subs = rng.randint(2, 8)
        for s in range(subs):
            big = p == big_pkg and s == 0
            count = args.big if big else rng.randint(3, 30)
            for m in range(count):
                if big:
                    size = 0 if rng.random() < 0.5 else min(int(200 * rng.paretovariate(0.9)), 91_000)
                else:
                    size = 0 if rng.random() < 0.1 else int(rng.lognormvariate(8.0, 1.5))
                cluster = rng.choice(clusters)
                names = sorted(set(rng.sample(cluster, rng.randint(1, 6))
                                   + rng.sample(pool, rng.randint(0, 2))))
                leaves.append((f"pkg{p:02d}/sub{s}/mod{m:04d}.py", size, names))
    return leaves


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--root", help="folder of Python modules to walk")
    ap.add_argument("--generate", action="store_true", help="a generated tree instead")
    ap.add_argument("--big", type=int, default=1826, help="modules of the big subpackage")
    ap.add_argument("--packages", type=int, default=89)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.generate == bool(args.root):
        ap.error("give exactly one of --root and --generate")
    leaves = generate(args) if args.generate else real(args.root)

    root = {"id": "site-packages", "name": "site-packages", "similarityMeasure": "jaccard",
            "weightAttribute": "size", "children": []}
    folders = {"": root}

    def folder(rel):
        if rel in folders:
            return folders[rel]
        parent = folder(os.path.dirname(rel))
        node = {"id": rel + "/", "name": os.path.basename(rel), "children": []}
        parent["children"].append(node)
        folders[rel] = node
        return node

    depth = 0
    for rel, size, names in leaves:
        leaf = {"id": rel, "name": os.path.basename(rel), "size": size, "embeddings": names}
        folder(os.path.dirname(rel))["children"].append(leaf)
        depth = max(depth, rel.count("/") + 1)
    with open(args.out, "w") as f:
        json.dump(root, f, separators=(",", ":"))
    widest = max(len(n["children"]) for n in folders.values())
    empty = sum(1 for _, size, _ in leaves if size == 0)
    print(f"{args.out}: {len(leaves)} modules ({empty} empty), {depth} levels, "
          f"largest diagram {widest} children", file=sys.stderr)


if __name__ == "__main__":
    main()
