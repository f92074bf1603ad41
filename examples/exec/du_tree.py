#!/usr/bin/env python3
"""An adapter for `format: exec`: turns `du -ab` output into hierarchy JSON.

nptreemap runs it as `python3 du_tree.py FILE...` (the config's `command:`
followed by the paths of its `files:`) and reads the tree from stdout. Every
line of a file is `BYTES<TAB>PATH`; paths that are a prefix of another are
folders, the rest are leaves weighed by their size. Files with the same name
in different folders (`mod.rs`, `tests.rs`) are listed as neighbours, so the
layout keeps them side by side.

Errors go to stderr with a non-zero exit; nptreemap quotes them.
"""
import json
import sys
from collections import defaultdict


def read(paths):
    sizes = {}
    for path in paths:
        with open(path, encoding="utf-8") as f:
            for number, line in enumerate(f, 1):
                line = line.rstrip("\n")
                if not line:
                    continue
                size, sep, name = line.partition("\t")
                if not sep or not size.isdigit():
                    sys.exit(f"{path}: line {number}: expected BYTES<TAB>PATH, got {line!r}")
                sizes[name.strip("/")] = int(size)
    return sizes


def tree(sizes):
    folders = {p.rsplit("/", 1)[0] for p in sizes if "/" in p}
    leaves = sorted(p for p in sizes if p not in folders)
    by_name = defaultdict(list)
    for leaf in leaves:
        by_name[leaf.rsplit("/", 1)[-1]].append(leaf)
    root = {"id": "root", "name": "sizes", "children": []}
    nodes = {"": root}

    def node(path):
        if path not in nodes:
            parent, _, name = path.rpartition("/")
            nodes[path] = {"id": path, "name": name, "children": []}
            node(parent)["children"].append(nodes[path])
        return nodes[path]

    for leaf in leaves:
        n = node(leaf)
        del n["children"]
        n["value"] = max(sizes[leaf], 1)
        same = [other for other in by_name[n["name"]] if other != leaf]
        if same:
            n["neighbors"] = same
    root["useNeighborLeafs"] = True
    return root


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: du_tree.py DU_OUTPUT...")
    json.dump(tree(read(sys.argv[1:])), sys.stdout, indent=1)
