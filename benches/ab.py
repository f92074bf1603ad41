#!/usr/bin/env python3
"""Before and after in one run: two nptreemap binaries (and thread counts) alternated
on the same inputs, for BENCHMARKS.md (issue 34).

For every case, seed and method, `nptreemap bench INPUT --method M --seed S
--repeat 1` runs in a fresh process once per variant, the variants interleaved so
that load drifts hit them alike; a variant is a binary and a `-j` thread count (`all`: no `-j`, every core).
Reports medians over the seeds (layout time, peak RSS, per-diagram area error,
unconverged diagrams) and each variant's time as a ratio to the first variant's.

Cases are benches/scale.py's (flat10000, h20000, cheaders, ...) plus
`sitegen` (benches/site_packages.py --generate: 9,294 modules, one diagram of
1,826 half empty), `sitepkgs` (benches/site_packages.py --root FOLDER, with
--site-root) and `nosim-CASE`, CASE without its similarity (the plain treemap of the
same shape, the issue's baseline); a case ending in `.json` is that file.

    python3 benches/ab.py --variants before=/tmp/np-before:2,after=target/release/nptreemap:2 \\
        --cases sitegen,h20000 --methods plain,neighbor --seeds 1,2,3
    python3 benches/ab.py --variants j1=target/release/nptreemap:1,j2=target/release/nptreemap:2 \\
        --cases h20000 --methods plain,neighbor

Prints a Markdown table. Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers  # noqa: E402
import scale  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "target" / "scale"


def case_input(name: str, site_root: str | None) -> Path:
    if name.endswith(".json"):
        return Path(name)
    if name.startswith("nosim-"):
        src = case_input(name[len("nosim-"):], site_root)
        path = OUT / f"{name}.json"
        if not path.exists():
            doc = json.loads(src.read_text())
            for key in ("similarityMeasure", "useNeighborLeafs", "simAttribute"):
                doc.pop(key, None)

            def strip(node):
                node.pop("embeddings", None)
                node.pop("neighbors", None)
                for c in node.get("children", []):
                    strip(c)
            strip(doc)
            path.write_text(json.dumps(doc, separators=(",", ":")))
        return path
    if name in ("sitegen", "sitepkgs"):
        path = OUT / f"{name}.json"
        if not path.exists():
            src = ["--generate"] if name == "sitegen" else ["--root", site_root or "/tmp/sp"]
            subprocess.run([sys.executable, str(REPO / "benches" / "site_packages.py"),
                            str(path), *src], check=True)
        return path
    leaves, depth = scale.CASES[name]
    return scale.generate(name, leaves, depth)


def weight_args(name: str) -> list:
    base = name[len("nosim-"):] if name.startswith("nosim-") else name
    return ["--weight", "weight"] if base in scale.CASES and scale.CASES[base][0] else []


def run(binary: str, threads: str, name: str, inp: Path, method: str, seed: int,
        timeout: float) -> dict:
    # "all": no -j (one thread per core; binaries before -j existed).
    jobs = [] if threads == "all" else ["-j", threads]
    cmd = [binary, *jobs, "bench", inp, *weight_args(name), "--method", method,
           "--seed", seed, "--repeat", 1]
    rc, out, err, secs, rss = scale.timed(cmd, timeout)
    line = peers.last_json_line(out, "nptreemap") if rc == 0 else None
    if line is None:
        return {"status": "failed", "note": peers.tail(err) or f"exit {rc}"}
    return {"status": "ok", "time_ms": line["time_ms"], "rss_mb": rss / 1024.0,
            "error_max": line.get("area_error_diagram_max"),
            "unconverged": line.get("unconverged"), "constraints": line.get("constraints"),
            "realized": line.get("realized"), "leaves": line.get("leaves")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variants", required=True,
                    help="comma-separated NAME=BINARY:THREADS; ratios are to the first")
    ap.add_argument("--cases", required=True)
    ap.add_argument("--methods", default="plain,neighbor")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--site-root", help="the folder of the sitepkgs case")
    ap.add_argument("--timeout", type=float, default=600.0)
    args = ap.parse_args(argv)
    variants = []
    for v in args.variants.split(","):
        name, rest = v.split("=", 1)
        binary, threads = rest.rsplit(":", 1)
        variants.append((name, binary, threads))
    seeds = [int(s) for s in args.seeds.split(",")]
    methods = args.methods.split(",")
    OUT.mkdir(parents=True, exist_ok=True)
    env = (f"{dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M} UTC, {os.cpu_count()} cores, "
           f"load {os.getloadavg()[0]:.1f} at the start, revision {peers.git_revision() or '?'}")
    rows = []
    for case in args.cases.split(","):
        inp = case_input(case, args.site_root)
        for method in methods:
            runs = {v[0]: [] for v in variants}
            for seed in seeds:
                for name, binary, threads in variants:
                    print(f"{case} {method} seed {seed} {name} ...", file=sys.stderr, flush=True)
                    runs[name].append(run(binary, threads, case, inp, method, seed, args.timeout))
            rows.append((case, method, runs))
    print(f"A/B run, {env}; `python3 benches/ab.py {' '.join(argv or sys.argv[1:])}`. "
          f"Medians over seeds {args.seeds}; time is the layout step (`nptreemap bench`, fresh "
          "process per run), ratio = the first variant's time / this one's.\n")
    names = [v[0] for v in variants]
    print("| case | method | leaves | " + " | ".join(
        f"{n} time | {n} RSS | {n} error max / unconverged" for n in names) + " | ratios |")
    print("|---|---|---|" + "---|---|---|" * len(names) + "---|")

    def med(rs, key):
        vals = [r[key] for r in rs if r.get("status") == "ok" and r.get(key) is not None]
        return statistics.median(vals) if vals else None
    for case, method, runs in rows:
        leaves = med(runs[names[0]], "leaves") or med(runs[names[-1]], "leaves") or 0
        cells = []
        base = med(runs[names[0]], "time_ms")
        ratios = []
        for n in names:
            t = med(runs[n], "time_ms")
            cells.append(f"{scale.fmt(t, ',.0f', ' ms')} | {scale.fmt(med(runs[n], 'rss_mb'), '.0f', ' MB')}"
                         f" | {scale.fmt(med(runs[n], 'error_max'), '.4f')} / "
                         f"{scale.fmt(med(runs[n], 'unconverged'), '.0f')}")
            if n != names[0] and base and t:
                ratios.append(f"{n} {base / t:.2f}×")
        failed = [f"{n}: {r.get('note', '')[:80]}" for n in names for r in runs[n]
                  if r.get("status") != "ok"]
        print(f"| {case} | {method} | {leaves:,.0f} | " + " | ".join(cells) + " | "
              + ", ".join(ratios) + " |" + (f" failed: {'; '.join(failed)}" if failed else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
