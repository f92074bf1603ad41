#!/usr/bin/env python3
"""How nptreemap scales: sizes x (time, peak RSS, realised constraints, aspect,
area error) for `plain` and `neighbor`, with d3-voronoi-treemap beside `plain`
where it runs (issue 12, item 7).

Inputs are seeded similarity hierarchies from benches/gen_similar.py (64-d
random-walk embeddings, lognormal weights; "flat" = one level, "h" = 3
levels), written to target/scale/; "cheaders" is this machine's /usr/include
through benches/c_headers.py (issue 23's C-headers-like tree). For every case, method and seed it runs
`nptreemap bench INPUT --method M --seed S --repeat 1` in a fresh process:
time is the layout alone (parsing excluded), peak RSS is the process's
(os.wait4), and realised constraints (all levels), leaf aspect ratio and
per-diagram area error are the tool's own measures, which the suite checks
against the independent checker. d3 runs through ../shared/peers (the
harness benches/peers.py uses) on the same files, seed 1, one process,
where the peer can run (flat sets above 3,000 leaves fail in d3). With
--outputs, each case is also built once with `nptreemap build` (layout JSON
and HTML page) and the sizes of both and of the state folder are reported.

Usage (from the repository root):
    python3 benches/scale.py                        # the default set, seeds 1-3
    python3 benches/scale.py --cases flat2000,h20000 --seeds 1,2,3,4,5
    python3 benches/scale.py --no-peer --no-build --timeout 600

Prints a Markdown table (also target/scale/report.md; raw figures in
target/scale/results.json) for BENCHMARKS.md: medians over the seeds, with
neighbor's time as a ratio to plain's in the same run. Exit 1 when an
nptreemap run failed. Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers  # noqa: E402  (the d3 harness helpers, same folder)

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "target" / "scale"

# name: (leaves, depth). Issue 12's targets are on flat 2,000 and 10,000,
# 20,000 and 100,000 in 3 levels, and a cold 500-leaf layout.
CASES = {
    "flat500": (500, 1),
    "flat1000": (1000, 1),
    "flat2000": (2000, 1),
    "flat10000": (10000, 1),
    "h1000": (1000, 3),
    "h10000": (10000, 3),
    "h20000": (20000, 3),
    "h100000": (100000, 3),
    # Issue 23's C-headers-like tree: this machine's /usr/include by
    # benches/c_headers.py (Jaccard sets of included names, 8+ levels); its
    # size is the machine's.
    "cheaders": (None, None),
}
DEFAULT = ["flat500", "flat1000", "flat2000", "h1000", "h10000", "h20000"]
METHODS = ["plain", "neighbor"]


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def generate(name: str, leaves, depth) -> Path:
    path = OUT / f"{name}.json"
    if not path.exists() and leaves is None:
        log(f"generating {path.relative_to(REPO)} from /usr/include ...")
        subprocess.run([sys.executable, str(REPO / "benches" / "c_headers.py"), str(path)],
                       check=True)
    elif not path.exists():
        log(f"generating {path.relative_to(REPO)} ...")
        subprocess.run([sys.executable, str(REPO / "benches" / "gen_similar.py"),
                        "--n", str(leaves), "--depth", str(depth), "--dim", "64",
                        "--seed", "1", "--out", str(path)], check=True)
    return path


def timed(cmd: list, timeout: float) -> tuple[int | None, str, str, float, int]:
    """Runs cmd; (exit code or None on timeout, stdout, stderr, seconds, peak RSS in KB).

    The child is reaped with os.wait4, which gives its own peak RSS (RUSAGE_CHILDREN
    would be the maximum over every child so far)."""
    t0 = time.monotonic()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen([str(c) for c in cmd], stdout=out, stderr=err)
        killer = threading.Timer(timeout, proc.kill)
        killer.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            killer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped: Popen must not wait
        secs = time.monotonic() - t0
        out.seek(0)
        err.seek(0)
        text_out = out.read().decode(errors="replace")
        text_err = err.read().decode(errors="replace")
    if proc.returncode == -9 and secs >= timeout:
        return None, text_out, text_err, secs, 0
    return proc.returncode, text_out, text_err, secs, usage.ru_maxrss


def weight_args(name: str) -> list:
    """gen_similar's files name their weight `weight`; c_headers.py's declare theirs."""
    return [] if CASES[name][0] is None else ["--weight", "weight"]


def run_ours(args, name: str, inp: Path, method: str, seed: int) -> dict:
    cmd = [args.bin, "bench", inp, *weight_args(name), "--method", method,
           "--seed", seed, "--repeat", 1]
    rc, out, err, secs, rss = timed(cmd, args.timeout)
    if rc is None:
        return {"status": "timeout", "note": f"> {args.timeout:g} s"}
    line = peers.last_json_line(out, "nptreemap")
    if rc != 0 or line is None:
        return {"status": "failed", "note": peers.tail(err) or f"exit {rc}"}
    return {"status": "ok", "time_ms": line["time_ms"], "rss_mb": rss / 1024.0,
            "realized": line.get("realized"), "constraints": line.get("constraints"),
            "aspect": line.get("aspect_ratio_mean"),
            "area_error": line.get("area_error_diagram_mean"),
            "unconverged": line.get("unconverged"), "leaves": line.get("leaves")}


def run_outputs(args, name: str, inp: Path) -> dict:
    """`nptreemap build` of the case (the neighbor method, the default seed) writing the layout
    JSON and the HTML page; their sizes and the state folder's (layout, manifest and
    cached constraints under `.nptreemap/`), in bytes."""
    folder = OUT / f"{name}-build"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    fields = "" if CASES[name][0] is None else "    fields: {weight: weight}\n"
    (folder / "nptreemap.yaml").write_text(
        f"datasets:\n  - name: {name}\n    format: hierarchy-json\n"
        f"    files: {{hierarchy: {json.dumps(str(inp))}}}\n{fields}"
        f"    outputs:\n      - path: out/{name}.json\n      - path: out/{name}.html\n")
    rc, _, err, secs, rss = timed([args.bin, "build", "--config", folder / "nptreemap.yaml"],
                                  args.timeout)
    if rc != 0:
        return {"status": "failed" if rc is not None else "timeout",
                "note": peers.tail(err) or f"exit {rc}"}
    state = folder / "out" / ".nptreemap"
    return {"status": "ok", "build_ms": secs * 1000.0, "rss_mb": rss / 1024.0,
            "json": (folder / "out" / f"{name}.json").stat().st_size,
            "html": (folder / "out" / f"{name}.html").stat().st_size,
            "state": sum(f.stat().st_size for f in state.rglob("*") if f.is_file())}


def run_d3(args, inp: Path, leaves: int, depth: int) -> dict:
    if depth == 1 and leaves > peers.PEER_FLAT_LIMIT:
        return {"status": "skipped", "note": "flat > 3,000: d3 fails there"}
    cmd = ["node", peers.PEER_DIR / "run.mjs", inp, "--seed", peers.PEER_SEED]
    rc, out, err, secs, rss = timed(cmd, args.peer_timeout)
    if rc is None:
        return {"status": "timeout", "note": f"> {args.peer_timeout:g} s"}
    line = peers.last_json_line(out, "d3-voronoi-treemap")
    if rc != 0 or line is None or line.get("error"):
        return {"status": "failed", "note": (peers.tail(err) or str(line))[:120]}
    return {"status": "ok", "time_ms": line.get("time_ms"), "rss_mb": rss / 1024.0,
            "aspect": line.get("aspect_bbox_mean"),
            "area_error": line.get("err_d3def_local_mean")}


def median(rows: list, key: str):
    vals = [r[key] for r in rows if r.get("status") == "ok" and r.get(key) is not None]
    return statistics.median(vals) if vals else None


def fmt(x, spec: str, unit: str = "") -> str:
    return "–" if x is None else f"{x:{spec}}{unit}"


def report(results: dict, args, env: dict) -> str:
    lines = [
        f"Scale run, {env['date']}, {env['machine']}, revision {env['revision']}; "
        f"`{env['command']}`. Medians over seeds {args.seeds}; time is the layout alone "
        "(`nptreemap bench`, fresh process per run), RSS the process's peak; realised "
        "constraints over all levels; aspect = mean leaf bounding-box long/short side; "
        "area error = mean per-diagram Σ|A − A*|/A(parent).",
        "",
        "| case | leaves | d3 time | plain time | neighbor time | neighbor / plain | "
        "d3 RSS | plain RSS | neighbor RSS | realised (neighbor / plain) | "
        "aspect d3 / plain / neighbor | area error plain / neighbor |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, res in results.items():
        p, n, d = res["plain"], res["neighbor"], res.get("d3", [])
        leaves = CASES[name][0] or median(n, "leaves") or 0
        tp, tn = median(p, "time_ms"), median(n, "time_ms")
        failed = [f"{m}: {r['status']} ({r.get('note', '')})" for m in METHODS
                  for r in res[m] if r.get("status") != "ok"]
        ratio = f"{tn / tp:.1f}×" if tp and tn else "–"
        d3 = d[0] if d else {"status": "not run"}
        d3t = fmt(d3.get("time_ms"), ",.0f", " ms") if d3.get("status") == "ok" else d3["status"]
        lines.append(
            f"| {name} | {leaves:,} | {d3t} | {fmt(tp, ',.0f', ' ms')} | "
            f"{fmt(tn, ',.0f', ' ms')} | {ratio} | "
            f"{fmt(d3.get('rss_mb'), '.0f', ' MB')} | {fmt(median(p, 'rss_mb'), '.0f', ' MB')} | "
            f"{fmt(median(n, 'rss_mb'), '.0f', ' MB')} | "
            f"{fmt(median(n, 'realized'), ',.0f')} / {fmt(median(p, 'realized'), ',.0f')} "
            f"of {fmt(median(n, 'constraints'), ',.0f')} | "
            f"{fmt(d3.get('aspect'), '.2f')} / {fmt(median(p, 'aspect'), '.2f')} / "
            f"{fmt(median(n, 'aspect'), '.2f')} | "
            f"{fmt(median(p, 'area_error'), '.4f')} / {fmt(median(n, 'area_error'), '.4f')} |"
            + (f" {'; '.join(failed)}" if failed else ""))
    sized = {name: res["outputs"] for name, res in results.items() if "outputs" in res}
    if sized:
        lines += ["", "Output sizes (`nptreemap build`, neighbor, one run; bytes per leaf "
                  "in brackets; state = `out/.nptreemap/`):", "",
                  "| case | build time | build RSS | layout JSON | HTML page | state |",
                  "|---|---|---|---|---|---|"]
        for name, o in sized.items():
            if o.get("status") != "ok":
                lines.append(f"| {name} | {o.get('status')}: {o.get('note', '')} | | | | |")
                continue
            leaves = CASES[name][0] or median(results[name]["neighbor"], "leaves") or 1
            size = lambda b: f"{b / 1e6:,.1f} MB ({b / leaves:,.0f} B)"  # noqa: E731
            lines.append(f"| {name} | {o['build_ms']:,.0f} ms | {o['rss_mb']:.0f} MB | "
                         f"{size(o['json'])} | {size(o['html'])} | {size(o['state'])} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default=",".join(DEFAULT),
                    help="comma-separated, from: " + ", ".join(CASES))
    ap.add_argument("--seeds", default="1,2,3", help="comma-separated seeds (default 1,2,3)")
    ap.add_argument("--bin", type=Path, default=REPO / "target" / "release" / "nptreemap")
    ap.add_argument("--no-build", action="store_true", help="skip `cargo build --release`")
    ap.add_argument("--no-peer", action="store_true", help="do not run d3")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per nptreemap run")
    ap.add_argument("--peer-timeout", type=float, default=300.0, help="seconds per d3 run")
    ap.add_argument("--shared", type=Path, default=peers.DEFAULT_SHARED)
    ap.add_argument("--outputs", action="store_true",
                    help="also build each case's layout JSON and page and report their "
                         "sizes and the state folder's")
    args = ap.parse_args(argv)
    names = [c.strip() for c in args.cases.split(",") if c.strip()]
    bad = [c for c in names if c not in CASES]
    if bad or not names:
        ap.error(f"unknown case(s) {bad}; choose from {', '.join(CASES)}")
    seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    OUT.mkdir(parents=True, exist_ok=True)
    if not args.no_build and peers.build_ours():
        return 1
    peer = not args.no_peer
    if peer:
        why = peers.install_peer(args.shared.resolve())
        if why:
            log(f"d3 not run: {why}")
            peer = False
    env = {"date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
           "machine": "{} cores, load {:.1f}".format(os.cpu_count(), os.getloadavg()[0]),
           "revision": peers.git_revision() or "?",
           "command": " ".join(["python3", "benches/scale.py", *(argv or sys.argv[1:])])}
    results, failed = {}, False
    for name in names:
        leaves, depth = CASES[name]
        inp = generate(name, leaves, depth)
        res = {m: [] for m in METHODS}
        # Seeds outermost and methods interleaved, so load drifts hit both alike.
        for seed in seeds:
            for method in METHODS:
                log(f"{name} {method} seed {seed} ...")
                r = run_ours(args, name, inp, method, seed)
                failed |= r["status"] != "ok"
                res[method].append(r)
        if args.outputs:
            log(f"{name} outputs ...")
            res["outputs"] = run_outputs(args, name, inp)
            failed |= res["outputs"]["status"] != "ok"
        if peer and leaves is not None:
            log(f"{name} d3 ...")
            res["d3"] = [run_d3(args, inp, leaves, depth)]
        results[name] = res
    text = report(results, args, env)
    (OUT / "report.md").write_text(text)
    (OUT / "results.json").write_text(json.dumps({"env": env, "results": results}, indent=1))
    print(text)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
