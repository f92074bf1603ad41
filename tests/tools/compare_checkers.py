#!/usr/bin/env python3
"""Agreement check between the repository's layout checker and the shared one.

What this file owns: evidence that tests/tools/check_layout.py (the project's own
checker, which the tests run) and shared/tools/check-layout (the shared checker
beside the repository) reach the same verdicts and figures on the same files.

Usage:
  compare_checkers.py [--shared DIR] [--bin NPTREEMAP] [--work DIR] [FILE ...]

With FILEs, compares the two checkers on those layout JSON files. Without, builds
the default set under --work (default target/compare-checkers/) first:
  - every dataset of tests/data/paper laid out by `nptreemap layout` three ways:
    the default, `--method plain` and `--outline circle`;
  - hierarchies of tests/tools/gen.py (1,000 leaves at depth 3, 2,000 flat);
  - the layout JSON of the shipped examples (`nptreemap build` on a copy of
    examples/, so that examples/out/ stays untouched);
  - broken layouts derived from a good one (the countries): a leaf moved off the
    canvas, a leaf moved onto a cousin, a non-convex leaf, a leaf shrunk so that
    its siblings no longer cover their parent, a two-point polygon, a duplicate
    id, a contradicted `realized` flag, a constraint across depths; and one valid
    layout whose weights no longer match its areas (large area errors).
The binary defaults to target/release/nptreemap (`cargo build --release`).

For each file both checkers must agree on the verdict (exit status and `ok`), on
every count, and on every figure they both report to within 1e-9 (both round
their means the same way). `problems` are not compared: the wording differs and
the repository's checker enforces a few more rules (see its --help).

Exit status: 0 when all files agree, or when the shared checker is absent (a
message says the comparison was skipped); 1 on any disagreement; 2 on a setup
error (no binary, a layout run failed).
"""

import argparse
import copy
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
OURS = REPO / "tests" / "tools" / "check_layout.py"
PAPER = REPO / "tests" / "data" / "paper"
TOLERANCE = 1e-9
# Figures only the repository's checker reports, or that are text.
NOT_COMPARED = {"problems", "problem_count", "warnings", "checker", "error"}


def run_checker(script, path):
    p = subprocess.run([sys.executable, str(script), str(path)], capture_output=True, text=True)
    try:
        report = json.loads(p.stdout)
    except ValueError:
        report = {"unparsable output": p.stdout[-500:] + p.stderr[-500:]}
    return p.returncode, report


def differences(ours, theirs, where=""):
    """(list of disagreements, largest numeric difference) between two reports."""
    bad, worst = [], 0.0
    for key in sorted(set(ours) & set(theirs) - NOT_COMPARED):
        a, b, name = ours[key], theirs[key], where + key
        if isinstance(a, dict) and isinstance(b, dict):
            if set(a) != set(b):
                bad.append(f"{name}: keys {sorted(a)} vs {sorted(b)}")
            sub_bad, sub_worst = differences(a, b, name + ".")
            bad += sub_bad
            worst = max(worst, sub_worst)
        elif isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
            if a != b:
                bad.append(f"{name}: {a!r} vs {b!r}")
        elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
            diff = abs(a - b)
            if not math.isfinite(diff) or diff > TOLERANCE:
                bad.append(f"{name}: {a!r} vs {b!r}")
            else:
                worst = max(worst, diff)
        elif a != b:
            bad.append(f"{name}: {a!r} vs {b!r}")
    return bad, worst


def nptreemap(binary, *args):
    p = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"setup: nptreemap {' '.join(map(str, args))} failed:\n{p.stderr[-2000:]}")


def leaf_polygon_nodes(doc):
    parents = {n["parent"] for n in doc["nodes"] if n.get("parent") is not None}
    return [n for n in doc["nodes"] if n["id"] not in parents and n.get("parent") is not None]


def area(poly):
    return sum(poly[i - 1][0] * poly[i][1] - poly[i][0] * poly[i - 1][1] for i in range(len(poly))) / 2


def write(path, doc):
    path.write_text(json.dumps(doc))
    return path


def broken_files(good, out):
    """Deliberately broken variants of the layout file `good`."""
    base = json.loads(good.read_text())
    files = []
    width = base["canvas"]["width"]

    doc = copy.deepcopy(base)
    leaf = leaf_polygon_nodes(doc)[0]
    leaf["polygon"] = [[x + width, y] for x, y in leaf["polygon"]]
    files.append(write(out / "broken_leaf_outside_parent.json", doc))

    doc = copy.deepcopy(base)
    leaf = max(leaf_polygon_nodes(doc), key=lambda n: abs(area(n["polygon"])))
    shift = width / 3
    leaf["polygon"] = [[x + shift if x + shift <= width else x - shift, y] for x, y in leaf["polygon"]]
    files.append(write(out / "broken_leaf_over_a_cousin.json", doc))

    doc = copy.deepcopy(base)
    leaf = max(leaf_polygon_nodes(doc), key=lambda n: len(n["polygon"]))
    pts = leaf["polygon"]
    cx = sum(p[0] for p in pts) / len(pts)
    cy = sum(p[1] for p in pts) / len(pts)
    (ax, ay), (bx, by) = pts[0], pts[1]
    # a notch: the middle of the first edge pulled halfway to the centroid
    notch = [((ax + bx) / 2 + cx) / 2, ((ay + by) / 2 + cy) / 2]
    leaf["polygon"] = [pts[0], notch] + pts[1:]
    files.append(write(out / "broken_non_convex_leaf.json", doc))

    doc = copy.deepcopy(base)
    leaf = leaf_polygon_nodes(doc)[-1]
    pts = leaf["polygon"]
    cx = sum(p[0] for p in pts) / len(pts)
    cy = sum(p[1] for p in pts) / len(pts)
    leaf["polygon"] = [[cx + 0.9 * (x - cx), cy + 0.9 * (y - cy)] for x, y in pts]
    files.append(write(out / "broken_areas_do_not_sum.json", doc))

    doc = copy.deepcopy(base)
    if doc.get("constraints"):
        doc["constraints"][0]["realized"] = not doc["constraints"][0]["realized"]
        files.append(write(out / "broken_realized_flag.json", doc))

    doc = copy.deepcopy(base)
    leaf_polygon_nodes(doc)[1]["polygon"] = leaf_polygon_nodes(doc)[1]["polygon"][:2]
    files.append(write(out / "broken_two_point_polygon.json", doc))

    doc = copy.deepcopy(base)
    doc["nodes"][-1]["id"] = doc["nodes"][-2]["id"]
    files.append(write(out / "broken_duplicate_id.json", doc))

    # not broken, but far off its weights: the area errors must still agree
    doc = copy.deepcopy(base)
    for n in leaf_polygon_nodes(doc)[::2]:
        n["weight"] = 3 * n["weight"]
    files.append(write(out / "weights_off.json", doc))

    doc = copy.deepcopy(base)
    root = next(n for n in doc["nodes"] if n.get("parent") is None)
    deep = leaf_polygon_nodes(doc)[0]
    doc.setdefault("constraints", []).append(
        {"a": root["id"], "b": deep["id"], "similarity": 0.5, "strength": 2, "realized": False})
    files.append(write(out / "broken_constraint_across_depths.json", doc))
    return files


def default_set(binary, work):
    if not binary.exists():
        sys.exit(f"setup: {binary} is missing; run `cargo build --release` first, or pass --bin")
    layouts = work / "layouts"
    if work.exists():
        shutil.rmtree(work)
    layouts.mkdir(parents=True)
    files = []
    for data in sorted(PAPER.glob("*.json")):
        for tag, extra in (("default", []), ("plain", ["--method", "plain"]),
                           ("circle", ["--outline", "circle"])):
            out = layouts / f"{data.stem}.{tag}.json"
            nptreemap(binary, "layout", data, "--out", out, *extra)
            files.append(out)
    generated = work / "generated"
    generated.mkdir()
    for n, depth in ((1000, 3), (2000, 1)):
        tree = generated / f"gen_{n}_{depth}.json"
        p = subprocess.run([sys.executable, str(REPO / "tests" / "tools" / "gen.py"), "--n", str(n),
                            "--depth", str(depth), "--seed", "1", "--out", str(tree)], capture_output=True)
        if p.returncode != 0:
            sys.exit(f"setup: gen.py failed: {p.stderr.decode()[-2000:]}")
        out = layouts / f"gen_{n}_{depth}.json"
        nptreemap(binary, "layout", tree, "--out", out)
        files.append(out)
    examples = work / "examples"
    shutil.copytree(REPO / "examples", examples, ignore=shutil.ignore_patterns("out", "*.rs"))
    nptreemap(binary, "build", examples / "nptreemap.yaml")
    files += sorted((examples / "out").glob("*.json"))
    broken = work / "broken"
    broken.mkdir()
    files += broken_files(layouts / "country_pop_50M_AUS.default.json", broken)
    return files


def main(argv=None):
    ap = argparse.ArgumentParser(prog="compare_checkers.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", type=Path, help="layout JSON files (default: build the set)")
    ap.add_argument("--shared", type=Path, default=REPO / ".." / "shared",
                    help="the shared folder holding tools/check-layout (default ../shared)")
    ap.add_argument("--bin", type=Path, default=REPO / "target" / "release" / "nptreemap",
                    help="the nptreemap binary for the default set")
    ap.add_argument("--work", type=Path, default=REPO / "target" / "compare-checkers",
                    help="where the default set is written")
    args = ap.parse_args(argv)

    theirs = args.shared / "tools" / "check-layout"
    if not theirs.is_file():
        print(f"compare_checkers: skipped, no shared checker at {theirs}")
        return 0
    files = args.files or default_set(args.bin, args.work)

    disagreements, worst, valid = 0, 0.0, 0
    for path in files:
        code_o, ours = run_checker(OURS, path)
        code_t, rep_t = run_checker(theirs, path)
        bad, diff = differences(ours, rep_t)
        if code_o != code_t:
            bad.insert(0, f"exit status {code_o} vs {code_t}")
        if ours.get("ok") != rep_t.get("ok"):
            bad.insert(0, f"ok {ours.get('ok')} vs {rep_t.get('ok')}")
        worst = max(worst, diff)
        valid += code_o == 0
        verdict = "valid" if code_o == 0 else f"invalid ({ours.get('problem_count')} problems)"
        if bad:
            disagreements += 1
            print(f"DISAGREE {path}: " + "; ".join(bad))
        else:
            print(f"agree    {path.name}: {verdict}, "
                  f"realized_lowest {ours.get('realized_lowest')}/{ours.get('constraints_lowest')}, "
                  f"max difference {diff:.3g}")
    print(f"\n{len(files)} files compared ({valid} valid, {len(files) - valid} invalid): "
          f"{disagreements} disagreements, largest numeric difference {worst:.3g}")
    return 1 if disagreements else 0


if __name__ == "__main__":
    sys.exit(main())
