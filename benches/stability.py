#!/usr/bin/env python3
"""Warm start against cold layout after a one-leaf edit (issue 6 items 2 and 6).

For a 500-leaf hierarchy with embeddings (benches/gen_similar.py, default method
`neighbor`) and a plain 500-leaf hierarchy (shared/peers/gen.py, method `plain`):

  1. lays the base data out cold: `nptreemap layout BASE --out old.json`;
  2. for each of --edits leaves spread over the tree, scales that one leaf's
     weight by --factor (default 1.1, a 10% change) and times
     `nptreemap bench EDITED --previous old.json` (warm) and the same with
     `--cold`, --runs fresh processes of --repeat layouts each, median of the
     per-process medians (prepare + constraints + layout; parsing excluded);
  3. takes the stability figures from the same bench lines: mean centroid
     displacement of the unchanged leaves (share of the canvas diagonal) and the
     share of the constraints realised in old.json still realised.

Prints a Markdown report for BENCHMARKS.md with issue 6's acceptance checks:
warm >= 3x faster, unchanged leaves move <= 1% of the diagonal, >= 95% of the
realised constraints kept, and a cold layout moving them >= 5x more.

usage: python3 benches/stability.py [--bin PATH] [--no-build] [--edits 5]
       [--factor 1.1] [--leaves 500] [--runs 3] [--repeat 3]
Python 3 standard library only; needs cargo unless --no-build.
"""
import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from peers import git_revision, machine_info  # noqa: E402  (same folder)

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO / ".." / "shared"
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))


def run_json(cmd):
    """Runs cmd and returns its last stdout line as JSON."""
    out = subprocess.run([str(c) for c in cmd], check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def leaves(node):
    kids = node.get("children") or []
    if not kids:
        yield node
    for k in kids:
        yield from leaves(k)


def make_inputs(work, n, seed):
    """The two base files: (case name, path, method)."""
    similar = work / f"similar{n}.json"
    subprocess.run([sys.executable, REPO / "benches" / "gen_similar.py", "--n", str(n),
                    "--depth", "3", "--dim", "32", "--seed", str(seed), "--out", similar],
                   check=True)
    plain = work / f"plain{n}.json"
    subprocess.run([sys.executable, SHARED / "peers" / "gen.py", "--n", str(n), "--depth", "3",
                    "--seed", str(seed), "--out", plain], check=True, capture_output=True)
    return [("similarity", similar, "neighbor"), ("plain", plain, "plain")]


def edited(base, k, factor, out):
    """base with the k-th leaf's weight scaled by factor; returns the leaf's id."""
    tree = json.loads(base.read_text())
    leaf = list(leaves(tree))[k]
    leaf["weight"] = leaf["weight"] * factor
    out.write_text(json.dumps(tree))
    return leaf.get("id", leaf.get("name"))


def bench(binary, inp, method, previous, cold, runs, repeat):
    """Median over fresh processes of `nptreemap bench`; the last line's figures."""
    cmd = [binary, "bench", inp, "--method", method, "--previous", previous,
           "--repeat", str(repeat)]
    if cold:
        cmd.append("--cold")
    lines = [run_json(cmd) for _ in range(runs)]
    line = dict(lines[-1])
    line["time_ms"] = statistics.median(x["time_ms"] for x in lines)
    return line


def pct(x):
    return "—" if x is None else f"{100 * x:.4f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", type=Path, default=TARGET / "release" / "nptreemap")
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--leaves", type=int, default=500)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--edits", type=int, default=5, help="edited leaves, one at a time")
    ap.add_argument("--factor", type=float, default=1.1, help="weight factor of the edit")
    ap.add_argument("--runs", type=int, default=3, help="fresh processes per timing")
    ap.add_argument("--repeat", type=int, default=3, help="layouts per process")
    args = ap.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=REPO, check=True)
    work = TARGET / "bench" / "stability"
    work.mkdir(parents=True, exist_ok=True)

    report = [
        "## Warm start vs cold layout after a one-leaf edit (`benches/stability.py`)",
        "",
        f"- date: {dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M} UTC; "
        f"nptreemap {git_revision() or '?'}",
    ]
    m = machine_info()
    report.append(f"- machine: {m['nproc']} CPUs, {m['cpu']}, load {m['loadavg']}")
    report.append("- command: `" + " ".join(["python3 benches/stability.py"] + sys.argv[1:]) + "`")
    report.append(f"- each edit scales one leaf's weight by {args.factor}; times are medians of "
                  f"{args.runs} processes × {args.repeat} layouts (prepare + constraints + layout)")
    report.append("- moved: mean centroid displacement of the unchanged leaves, % of the canvas "
                  "diagonal; kept: % of the constraints realised before that still are")
    report.append("")
    failures = []
    for case, base, method in make_inputs(work, args.leaves, args.seed):
        old = work / f"{case}_old.json"
        subprocess.run([args.bin, "layout", base, "--method", method, "--out", old], check=True)
        n = sum(1 for _ in leaves(json.loads(base.read_text())))
        report += [f"### {case}: {n} leaves, method `{method}`", "",
                   "| edited leaf | warm ms | cold ms | speed-up | warm ticks | cold ticks "
                   "| warm moved % | cold moved % | cold/warm | warm kept % | cold kept % |",
                   "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"]
        rows = []
        for e in range(args.edits):
            k = (e + 1) * n // (args.edits + 1)
            inp = work / f"{case}_edit{e}.json"
            leaf = edited(base, k, args.factor, inp)
            warm = bench(args.bin, inp, method, old, False, args.runs, args.repeat)
            cold = bench(args.bin, inp, method, old, True, args.runs, args.repeat)
            if warm["start"] != "warm":
                failures.append(f"{case} {leaf}: the previous layout was not used")
            speedup = cold["time_ms"] / warm["time_ms"]
            wm, cm = warm["displacement_unchanged_mean"], cold["displacement_unchanged_mean"]
            ratio = cm / wm if wm > 0 else float("inf")
            rows.append((speedup, wm, ratio, warm["kept_share"], cold["kept_share"]))
            report.append(
                f"| {leaf} | {warm['time_ms']:.1f} | {cold['time_ms']:.1f} | {speedup:.0f}× "
                f"| {warm['iterations']} | {cold['iterations']} | {pct(wm)} | {pct(cm)} "
                f"| {ratio:.0f}× | {pct(warm['kept_share'])} | {pct(cold['kept_share'])} |")
        worst_speedup = min(r[0] for r in rows)
        worst_moved = max(r[1] for r in rows)
        worst_ratio = min(r[2] for r in rows)
        kept = [r[3] for r in rows if r[3] is not None]
        report += ["", f"Worst over the edits: speed-up {worst_speedup:.1f}×, warm moved "
                       f"{pct(worst_moved)}% of the diagonal, cold/warm {worst_ratio:.1f}×"
                       + (f", warm kept {pct(min(kept))}%" if kept else "") + ".", ""]
        checks = [("unchanged leaves move <= 1% of the diagonal", worst_moved <= 0.01),
                  ("a cold layout moves them >= 5x more", worst_ratio >= 5)]
        if kept:
            checks.append((">= 95% of realised constraints kept", min(kept) >= 0.95))
        if method == "neighbor":
            checks.append(("warm >= 3x faster than cold", worst_speedup >= 3))
        for name, ok in checks:
            report.append(f"- {'PASS' if ok else 'FAIL'}: {name}")
            if not ok:
                failures.append(f"{case}: {name}")
        report.append("")
    text = "\n".join(report)
    print(text)
    (work / "report.md").write_text(text + "\n")
    for f in failures:
        print(f"FAILED: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
