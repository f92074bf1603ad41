#!/usr/bin/env python3
"""A C-headers-like hierarchy from a real source tree, for benches/incremental.py.

Walks a folder (default /usr/include) and writes hierarchy JSON: one leaf per
header file (`*.h`, `*.hpp`, `*.hh`), nested in its folders, weighted by its
size in bytes, with the Jaccard similarity of the names it `#include`s (each
leaf carries the set of those names as a list of strings; the root declares
`similarityMeasure: jaccard` and `weightAttribute: size`). `--one-hot` writes
the older form instead: each leaf's one-hot vector over all distinct names
(the same dataset once read, issue 23, but a file of leaves x names numbers).
Folders with a single child folder are kept, so the depth is the tree's own.

    python3 benches/c_headers.py OUT.json [--root /usr/include] [--leaves N] [--one-hot]

`--leaves N` keeps N headers spread evenly over the sorted list (the same
folders, fewer files). Prints the leaf count, depth and distinct names on
stderr. Standard library only; deterministic for a given tree.
"""

import argparse
import json
import os
import re
import sys

INCLUDE = re.compile(rb'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.MULTILINE)
SUFFIXES = (".h", ".hpp", ".hh")
# Files larger than this are read only this far for their includes.
READ_CAP = 1 << 20


def headers(root):
    found = []
    for folder, dirs, files in os.walk(root, followlinks=False):
        dirs.sort()
        for name in sorted(files):
            path = os.path.join(folder, name)
            if name.endswith(SUFFIXES) and os.path.isfile(path) and not os.path.islink(path):
                found.append(os.path.relpath(path, root))
    found.sort()
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--root", default="/usr/include")
    ap.add_argument("--leaves", type=int, default=0, help="keep this many headers (0: all)")
    ap.add_argument(
        "--one-hot",
        action="store_true",
        help="write one-hot vectors over all names instead of lists of names",
    )
    args = ap.parse_args()

    files = headers(args.root)
    if args.leaves and args.leaves < len(files):
        step = len(files) / args.leaves
        files = [files[int(i * step)] for i in range(args.leaves)]
    includes = {}
    sizes = {}
    for rel in files:
        path = os.path.join(args.root, rel)
        with open(path, "rb") as f:
            text = f.read(READ_CAP)
        sizes[rel] = os.path.getsize(path)
        includes[rel] = sorted({m.decode("utf-8", "replace") for m in INCLUDE.findall(text)})
    names = sorted({n for rel in files for n in includes[rel]})
    index = {n: i for i, n in enumerate(names)}

    root = {
        "id": "include",
        "name": os.path.basename(os.path.normpath(args.root)) or "include",
        "similarityMeasure": "jaccard",
        "weightAttribute": "size",
        "children": [],
    }
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
    for rel in files:
        if args.one_hot:
            features = [0] * len(names)
            for n in includes[rel]:
                features[index[n]] = 1
        else:
            features = includes[rel]
        leaf = {"id": rel, "name": os.path.basename(rel), "size": sizes[rel], "embeddings": features}
        folder(os.path.dirname(rel))["children"].append(leaf)
        depth = max(depth, rel.count("/") + 1)
    with open(args.out, "w") as f:
        json.dump(root, f, separators=(",", ":"))
    print(
        f"{args.out}: {len(files)} headers, {depth} levels, {len(names)} distinct included names",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
