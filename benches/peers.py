#!/usr/bin/env python3
"""Side-by-side benchmark: nptreemap vs d3-voronoi-treemap, same run, same inputs.

Generates seeded inputs with shared/peers/gen.py, times both tools on each of
them in fresh processes, re-checks nptreemap's layout with the independent
shared/tools/check-layout, and prints a Markdown report (also written to
target/bench/report.md, raw figures to target/bench/results.json) ready to
paste into BENCHMARKS.md.

Usage (from the repository root):
    python3 benches/peers.py                  # full run: h1000 h10000 flat2000 flat10000
    python3 benches/peers.py --quick          # smoke run: h100 h1000 flat500
    python3 benches/peers.py --cases h1000,flat2000 --runs 5
    python3 benches/peers.py --quick --peer-only     # d3 side only, no cargo build
    python3 benches/peers.py --no-build --bin path/to/nptreemap

Cases (N leaves; "h" = hierarchy of depth 3, "flat" = depth 1, all --seed 1):
    h100 h1000 h10000 flat500 flat2000 flat10000

What is measured
  d3-voronoi-treemap: `node target/d3peer/run.mjs INPUT --seed peer-bench-1`,
    --runs fresh processes (each with --peer-timeout); median of their
    `time_ms` (cold layout in a fresh process, parsing excluded).  Area error
    `err_d3def_local_mean` and aspect ratio `aspect_bbox_mean` from its output.
    Flat sets above ~3,000 siblings are skipped unless --peer-flat-10k.
  nptreemap: `nptreemap bench INPUT --weight weight --seed 1 --repeat 3
    --convergence 0.01`, --runs fresh processes; median of the per-process
    medians.  Then `nptreemap layout INPUT --out target/bench/CASE.json` once
    and `check-layout` on it: the report's area error and aspect ratio for
    nptreemap are the checker's, not the tool's own.
  Both tools use the same area-error target (d3's default convergence ratio 0.01).

Exit status: 0 when nptreemap built, ran and passed check-layout on every case
(peer failures and timeouts are only reported), 1 otherwise, 2 on usage errors.
Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import shlex
import shutil
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SHARED = REPO / ".." / "shared"
BENCH_DIR = REPO / "target" / "bench"
PEER_DIR = REPO / "target" / "d3peer"

CONVERGENCE = 0.01          # d3-voronoi-map's default convergenceRatio
PEER_SEED = "peer-bench-1"
OUR_SEED = 1
OUR_REPEAT = 3
GEN_SEED = 1
PEER_FLAT_LIMIT = 3000      # d3 fails beyond ~3,000 siblings in one polygon
PEER_FLAT_SKIP_NOTE = ("not run (d3 fails beyond ~3,000 siblings, "
                       "see shared/peers/README.md)")


# --------------------------------------------------------------------------- cases

@dataclass(frozen=True)
class Case:
    name: str
    leaves: int
    depth: int

    @property
    def label(self) -> str:
        return f"depth {self.depth}" if self.depth > 1 else "flat"


ALL_CASES = {c.name: c for c in [
    Case("h100", 100, 3),
    Case("h1000", 1000, 3),
    Case("h10000", 10000, 3),
    Case("flat500", 500, 1),
    Case("flat2000", 2000, 1),
    Case("flat10000", 10000, 1),
]}
FULL_SET = ["h1000", "h10000", "flat2000", "flat10000"]
QUICK_SET = ["h100", "h1000", "flat500"]


# --------------------------------------------------------------------------- results

@dataclass
class PeerResult:
    status: str = "not run"            # ok | timeout | failed | skipped | not run
    note: str = ""
    times_ms: list = field(default_factory=list)
    time_ms: float | None = None
    area_error: float | None = None    # err_d3def_local_mean
    aspect: float | None = None        # aspect_bbox_mean
    nodes_above_ratio: int | None = None
    empty_leaves: int | None = None
    leaves: int | None = None
    versions: dict = field(default_factory=dict)


@dataclass
class OurResult:
    status: str = "not run"            # ok | error | not run
    errors: list = field(default_factory=list)
    runs: list = field(default_factory=list)       # parsed bench JSON lines
    time_ms: float | None = None                   # median of per-process medians
    own_area_error: float | None = None            # tool's own area_error_diagram_mean
    own_area_error_max: float | None = None
    iterations: list = field(default_factory=list)
    unconverged: list = field(default_factory=list)
    check: dict | None = None                      # check-layout output
    area_error: float | None = None                # checker's area_error_diagram_mean
    aspect: float | None = None                    # checker's aspect_ratio_mean


# --------------------------------------------------------------------------- helpers

def log(msg: str) -> None:
    print(f"[peers] {msg}", file=sys.stderr, flush=True)


def rel(p: Path) -> str:
    """Path relative to the repo root when possible (for readable logs/reports)."""
    try:
        return str(Path(os.path.relpath(p, REPO)))
    except ValueError:
        return str(p)


@dataclass
class Proc:
    rc: int | None          # None on timeout
    stdout: str
    stderr: str
    seconds: float

    @property
    def timed_out(self) -> bool:
        return self.rc is None


def run(cmd: list, timeout: float | None = None, cwd: Path | None = None) -> Proc:
    """Run cmd, capture output; a timeout kills the process and returns rc=None."""
    t0 = time.monotonic()
    try:
        cp = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True,
                            text=True, timeout=timeout)
        return Proc(cp.returncode, cp.stdout, cp.stderr, time.monotonic() - t0)
    except subprocess.TimeoutExpired as e:
        def txt(b):
            return b.decode(errors="replace") if isinstance(b, bytes) else (b or "")
        return Proc(None, txt(e.stdout), txt(e.stderr), time.monotonic() - t0)
    except OSError as e:
        return Proc(127, "", f"cannot run {cmd[0]}: {e}", time.monotonic() - t0)


def last_json_line(text: str, tool: str | None = None) -> dict | None:
    """The last stdout line that parses as a JSON object (optionally with "tool": tool)."""
    for line in reversed(text.strip().splitlines()):
        line = line.strip()
        if not line.startswith("{"):
            continue
        try:
            obj = json.loads(line)
        except ValueError:
            continue
        if isinstance(obj, dict) and (tool is None or obj.get("tool") == tool):
            return obj
    return None


def tail(text: str, n: int = 3) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return " | ".join(lines[-n:])


def num(x) -> float | None:
    """A finite float, or None (JSON null / NaN / missing / wrong type)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    x = float(x)
    return x if x == x and abs(x) != float("inf") else None


# --------------------------------------------------------------------------- inputs

def generate_inputs(cases: list, shared: Path) -> dict:
    """Write every case's input with gen.py; returns {case name: input path}."""
    gen = shared / "peers" / "gen.py"
    BENCH_DIR.mkdir(parents=True, exist_ok=True)
    paths = {}
    for c in cases:
        out = BENCH_DIR / f"{c.name}.input.json"
        p = run([sys.executable, gen, "--n", c.leaves, "--depth", c.depth,
                 "--seed", GEN_SEED, "--out", out])
        if p.rc != 0:
            raise SystemExit(f"gen.py failed for {c.name}: {tail(p.stderr)}")
        stats = last_json_line(p.stderr) or {}
        if stats.get("leaves") != c.leaves:
            raise SystemExit(f"gen.py wrote {stats.get('leaves')} leaves for {c.name}, "
                             f"expected {c.leaves}")
        log(f"input {rel(out)}: {json.dumps(stats)}")
        paths[c.name] = out
    return paths


# --------------------------------------------------------------------------- d3 peer

def install_peer(shared: Path) -> str | None:
    """Copy shared/peers/d3 to target/d3peer and `npm ci` if needed; error text or None."""
    src = shared / "peers" / "d3"
    PEER_DIR.mkdir(parents=True, exist_ok=True)
    for f in src.iterdir():
        if f.is_file():
            dst = PEER_DIR / f.name
            if dst.exists():
                dst.unlink()  # shared files are read-only; replace, don't overwrite
            shutil.copyfile(f, dst)
    if (PEER_DIR / "node_modules" / "d3-voronoi-treemap" / "package.json").exists():
        return None
    if not shutil.which("npm"):
        return "npm not found"
    log(f"npm ci in {rel(PEER_DIR)} ...")
    p = run(["npm", "ci", "--no-audit", "--no-fund"], cwd=PEER_DIR, timeout=600)
    if p.rc != 0:
        return "npm ci " + ("timed out" if p.timed_out else f"failed: {tail(p.stderr)}")
    return None


def peer_version() -> str | None:
    pj = PEER_DIR / "node_modules" / "d3-voronoi-treemap" / "package.json"
    try:
        return json.loads(pj.read_text()).get("version")
    except (OSError, ValueError):
        return None


def peer_skip_reason(case: Case, args) -> str | None:
    if case.depth == 1 and case.leaves > PEER_FLAT_LIMIT and not args.peer_flat_10k:
        return PEER_FLAT_SKIP_NOTE
    return None


def run_peer_once(inp: Path, args, res: PeerResult) -> bool:
    """One fresh d3 process; appends to res; returns False when the case should stop."""
    cmd = ["node", PEER_DIR / "run.mjs", inp, "--seed", PEER_SEED]
    p = run(cmd, timeout=args.peer_timeout)
    if p.timed_out:
        res.status, res.note = "timeout", f"timeout (> {args.peer_timeout:g} s)"
        return False
    out = last_json_line(p.stdout, "d3-voronoi-treemap")
    if p.rc != 0 or out is None:
        why = tail(p.stderr) or f"exit status {p.rc}, no JSON line"
        res.status, res.note = "failed", f"failed ({why[:200]})"
        return False
    if out.get("error"):
        res.status, res.note = "failed", f"failed ({str(out['error'])[:200]})"
        return False
    t = num(out.get("time_ms"))
    if t is None:
        res.status, res.note = "failed", "failed (no time_ms in output)"
        return False
    res.times_ms.append(t)
    # quality figures are deterministic for a fixed seed; keep the first run's
    if res.area_error is None:
        res.area_error = num(out.get("err_d3def_local_mean"))
        res.aspect = num(out.get("aspect_bbox_mean"))
        res.nodes_above_ratio = out.get("nodes_local_err_ge_convergenceRatio")
        res.empty_leaves = out.get("empty_leaves")
        res.leaves = out.get("n_leaves")
        res.versions = out.get("versions") or {}
    return True


# --------------------------------------------------------------------------- nptreemap

def build_ours() -> str | None:
    """`cargo build --release` in the repo; error text or None."""
    log("cargo build --release ...")
    try:  # cargo's output goes to stderr so stdout stays pure Markdown
        p = subprocess.run(["cargo", "build", "--release"], cwd=REPO, stdout=sys.stderr)
    except OSError as e:
        return f"cannot run cargo: {e}"
    return None if p.returncode == 0 else f"cargo build --release failed (exit {p.returncode})"


def our_version(bin_path: Path) -> str | None:
    p = run([bin_path, "--version"], timeout=30)
    if p.rc != 0:
        return None
    return p.stdout.strip() or None


def run_ours_once(case: Case, inp: Path, args, res: OurResult) -> bool:
    """One fresh `nptreemap bench` process; appends to res; False on error."""
    cmd = [args.bin, "bench", inp, "--weight", "weight", "--seed", OUR_SEED,
           "--repeat", OUR_REPEAT, "--convergence", CONVERGENCE]
    p = run(cmd, timeout=args.timeout)
    if p.timed_out:
        res.errors.append(f"bench timed out after {args.timeout:g} s")
        return False
    out = last_json_line(p.stdout, "nptreemap")
    if p.rc != 0 or out is None:
        res.errors.append(f"bench exit {p.rc}: {tail(p.stderr) or 'no JSON line'}")
        return False
    if out.get("leaves") != case.leaves:
        res.errors.append(f"bench reports {out.get('leaves')} leaves, expected {case.leaves}")
        return False
    if num(out.get("time_ms")) is None:
        res.errors.append("bench output has no numeric time_ms")
        return False
    res.runs.append(out)
    return True


def layout_and_check(case: Case, inp: Path, args, shared: Path, res: OurResult) -> None:
    """`nptreemap layout` once, then the independent check-layout on the result."""
    out_path = BENCH_DIR / f"{case.name}.json"
    if out_path.exists():
        out_path.unlink()
    cmd = [args.bin, "layout", inp, "--out", out_path, *shlex.split(args.layout_args)]
    p = run(cmd, timeout=args.timeout)
    if p.timed_out:
        res.errors.append(f"layout timed out after {args.timeout:g} s")
        return
    if p.rc != 0:
        res.errors.append(f"layout exit {p.rc}: {tail(p.stderr)}")
        return
    if not out_path.exists():
        res.errors.append(f"layout exited 0 but wrote no {rel(out_path)}")
        return
    checker = shared / "tools" / "check-layout"
    c = run([sys.executable, checker, out_path], timeout=args.timeout)
    try:
        report = json.loads(c.stdout)
    except ValueError:
        report = None
    if c.timed_out or not isinstance(report, dict):
        res.errors.append("check-layout " + ("timed out" if c.timed_out
                                             else f"exit {c.rc}: {tail(c.stderr or c.stdout)}"))
        return
    res.check = report
    res.area_error = num(report.get("area_error_diagram_mean"))
    res.aspect = num(report.get("aspect_ratio_mean"))
    if c.rc != 0 or not report.get("ok"):
        probs = "; ".join(report.get("problems", [])[:3])
        res.errors.append(f"check-layout failed ({report.get('problem_count')} problems: {probs})")
    if report.get("leaves") != case.leaves:
        res.errors.append(f"layout has {report.get('leaves')} leaves, expected {case.leaves}")


def summarize_ours(res: OurResult) -> None:
    if res.runs:
        res.time_ms = statistics.median(float(r["time_ms"]) for r in res.runs)
        first = res.runs[0]
        res.own_area_error = num(first.get("area_error_diagram_mean"))
        res.own_area_error_max = num(first.get("area_error_diagram_max"))
        res.iterations = [r.get("iterations") for r in res.runs]
        res.unconverged = [r.get("unconverged") for r in res.runs]
    res.status = "error" if res.errors else ("ok" if res.runs else "not run")


# --------------------------------------------------------------------------- driver

def bench_case(case: Case, inp: Path, args, shared: Path, peer_ok: str | None):
    """Measure one case; d3 and nptreemap processes are interleaved to share drift."""
    peer = PeerResult()
    ours = OurResult()
    skip = peer_skip_reason(case, args)
    if skip:
        peer.status, peer.note = "skipped", skip
    elif peer_ok is not None:
        peer.status, peer.note = "failed", f"failed ({peer_ok})"
    peer_active = peer.status == "not run"
    ours_active = not args.peer_only
    for i in range(args.runs):
        if peer_active:
            log(f"{case.name}: d3 run {i + 1}/{args.runs}")
            peer_active = run_peer_once(inp, args, peer)
            if peer_active:
                log(f"{case.name}: d3 {peer.times_ms[-1]:.1f} ms")
            else:
                log(f"{case.name}: d3 {peer.note}")
        if ours_active:
            log(f"{case.name}: nptreemap run {i + 1}/{args.runs}")
            ours_active = run_ours_once(case, inp, args, ours)
            if ours_active:
                log(f"{case.name}: nptreemap {float(ours.runs[-1]['time_ms']):.2f} ms")
    if peer.times_ms and peer.status == "not run":
        peer.status = "ok"
        peer.time_ms = statistics.median(peer.times_ms)
    if not args.peer_only:
        if not ours.errors:
            log(f"{case.name}: nptreemap layout + check-layout")
            layout_and_check(case, inp, args, shared, ours)
        summarize_ours(ours)
        for e in ours.errors:
            log(f"{case.name}: nptreemap ERROR: {e}")
    return peer, ours


# --------------------------------------------------------------------------- environment

def machine_info() -> dict:
    info = {"nproc": None, "cpu": platform.processor() or platform.machine(),
            "mem_gib": None, "loadavg": None, "os": platform.platform()}
    p = run(["nproc"], timeout=10)
    if p.rc == 0:
        info["nproc"] = p.stdout.strip()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                info["mem_gib"] = int(line.split()[1]) / 1024 / 1024
                break
    except OSError:
        pass
    try:
        info["loadavg"] = " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        pass
    return info


def node_version() -> str | None:
    p = run(["node", "--version"], timeout=30)
    return p.stdout.strip() if p.rc == 0 else None


def git_revision() -> str | None:
    p = run(["git", "describe", "--always", "--dirty"], cwd=REPO, timeout=30)
    return p.stdout.strip() if p.rc == 0 else None


# --------------------------------------------------------------------------- report

def fmt_ms(x: float | None) -> str:
    if x is None:
        return "—"
    if x >= 100:
        return f"{x:,.0f}"
    return f"{x:.1f}" if x >= 10 else f"{x:.2f}"


def fmt_err(x: float | None) -> str:
    if x is None:
        return "—"
    if x == 0:
        return "0"
    return f"{x:.4f}" if x >= 0.001 else f"{x:.1e}"


def fmt_ar(x: float | None) -> str:
    return "—" if x is None else f"{x:.2f}"


def fmt_speedup(d3: float | None, ours: float | None) -> str:
    if d3 is None or ours is None or ours <= 0:
        return "—"
    r = d3 / ours
    return f"{r:,.0f}×" if r >= 100 else f"{r:.1f}×"


def peer_cell(peer: PeerResult) -> str:
    return fmt_ms(peer.time_ms) if peer.status == "ok" else (peer.note or peer.status)


def our_time_cell(ours: OurResult, args) -> str:
    if args.peer_only:
        return "not run (--peer-only)"
    if ours.time_ms is None:
        return "error"
    return fmt_ms(ours.time_ms) + (" (error)" if ours.errors else "")


def our_err_cell(ours: OurResult) -> str:
    if ours.check is None:
        return "—"
    cell = fmt_err(ours.area_error)
    return cell if ours.check.get("ok") else f"{cell} (check FAILED)"


def render_report(cases, results, env, args) -> str:
    m = env["machine"]
    mem = f"{m['mem_gib']:.1f} GiB RAM" if m["mem_gib"] else "RAM unknown"
    d3v = env.get("d3_versions") or {}
    d3_line = f"d3-voronoi-treemap {env.get('d3_version') or 'unknown'}"
    extra = [f"{k} {v}" for k, v in d3v.items() if k not in ("d3-voronoi-treemap", "node")]
    if extra:
        d3_line += f" ({', '.join(extra)})"
    lines = [
        f"### Peer benchmark: nptreemap vs d3-voronoi-treemap{' (quick)' if args.quick else ''}",
        "",
        f"- Date (UTC): {env['date']}",
        f"- Machine: {m['nproc'] or '?'} CPUs (nproc), {m['cpu']}, {mem}; "
        f"load average at start {m['loadavg'] or '?'}, at end {m.get('loadavg_end') or '?'}",
        f"- Versions: {d3_line}; node {env.get('node') or 'not found'}; "
        f"nptreemap: {env.get('ours') or ('not run' if args.peer_only else 'unknown')}"
        f"{'' if not env.get('git') else ' (git ' + env['git'] + ')'}",
        f"- Command: `{env['command']}`",
        "",
        "| case | leaves | d3 time (ms) | d3 area error | nptreemap time (ms) "
        "| nptreemap area error (checker) | speed-up (d3/ours) | aspect ratio d3 / ours |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for c in cases:
        peer, ours = results[c.name]
        d3_time = peer.time_ms if peer.status == "ok" else None
        lines.append(
            f"| {c.name} ({c.label}) | {c.leaves:,} | {peer_cell(peer)} "
            f"| {fmt_err(peer.area_error) if peer.status == 'ok' else '—'} "
            f"| {our_time_cell(ours, args)} | {our_err_cell(ours)} "
            f"| {fmt_speedup(d3_time, ours.time_ms)} "
            f"| {fmt_ar(peer.aspect if peer.status == 'ok' else None)} / {fmt_ar(ours.aspect)} |")
    lines += [
        "",
        f"Times are layout only (input parsing excluded), {args.runs} fresh processes per tool "
        "and case, d3 and nptreemap processes interleaved. d3: median of the cold "
        f"`time_ms` of each process (`run.mjs --seed {PEER_SEED}`, 1000×1000 square, library "
        "defaults: convergence ratio 0.01, 50 iterations, min weight ratio 0.01). nptreemap: "
        f"median of the per-process medians of `bench --repeat {OUR_REPEAT} --seed {OUR_SEED} "
        f"--convergence {CONVERGENCE}`. Area error is the per-diagram "
        "Σ|A−T|/A_parent, mean over internal nodes (d3: `err_d3def_local_mean`; nptreemap: "
        "`area_error_diagram_mean` recomputed by `shared/tools/check-layout` from the polygons "
        "of one `nptreemap layout` run with its default settings unless the command line "
        "adds `--layout-args`; the tool's own figure from `bench` is in the details). "
        "Aspect ratio: mean bounding-box aspect of leaves.",
    ]
    lines += ["", *render_details(cases, results, args)]
    return "\n".join(lines) + "\n"


def render_details(cases, results, args) -> list:
    out = ["<details><summary>Per-run figures</summary>", "",
           "| case | d3 times (ms) | d3 nodes ≥ ratio | d3 empty leaves "
           "| nptreemap per-process medians (ms) | own area error mean / max "
           "| iterations | unconverged | check-layout |",
           "|---|---|---:|---:|---|---|---|---|---|"]
    for c in cases:
        peer, ours = results[c.name]
        d3t = ", ".join(fmt_ms(t) for t in peer.times_ms) or "—"
        if args.peer_only:
            our_cells = ["—"] * 5
        else:
            chk = "—"
            if ours.check is not None:
                chk = "ok" if ours.check.get("ok") else \
                    f"FAILED ({ours.check.get('problem_count')} problems)"
            our_cells = [
                ", ".join(fmt_ms(float(r["time_ms"])) for r in ours.runs) or "—",
                f"{fmt_err(ours.own_area_error)} / {fmt_err(ours.own_area_error_max)}",
                ", ".join(str(i) for i in ours.iterations) or "—",
                ", ".join(str(u) for u in ours.unconverged) or "—",
                chk,
            ]
        nz = lambda v: "—" if v is None else str(v)  # noqa: E731
        out.append(f"| {c.name} | {d3t} | {nz(peer.nodes_above_ratio)} "
                   f"| {nz(peer.empty_leaves)} | " + " | ".join(our_cells) + " |")
    errs = [(c.name, e) for c in cases for e in results[c.name][1].errors]
    if errs:
        out += ["", "nptreemap errors:", ""] + [f"- {n}: {e}" for n, e in errs]
    out += ["", "</details>"]
    return out


def write_outputs(report: str, cases, results, env) -> None:
    BENCH_DIR.mkdir(parents=True, exist_ok=True)
    (BENCH_DIR / "report.md").write_text(report)
    raw = {"env": env, "cases": {c.name: {"leaves": c.leaves, "depth": c.depth,
                                          "d3": vars(results[c.name][0]),
                                          "nptreemap": vars(results[c.name][1])}
                                 for c in cases}}
    (BENCH_DIR / "results.json").write_text(json.dumps(raw, indent=1, default=str) + "\n")


# --------------------------------------------------------------------------- main

def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: " + " ".join(QUICK_SET))
    ap.add_argument("--cases", help="comma-separated case names (overrides the set), "
                    "from: " + ", ".join(ALL_CASES))
    ap.add_argument("--runs", type=int, default=3,
                    help="fresh processes per tool and case (default 3)")
    ap.add_argument("--peer-timeout", type=float, default=120.0,
                    help="seconds per d3 process before it counts as 'timeout' (default 120)")
    ap.add_argument("--peer-flat-10k", action="store_true",
                    help=f"also run d3 on flat sets above {PEER_FLAT_LIMIT:,} leaves")
    ap.add_argument("--peer-only", action="store_true",
                    help="measure d3 only (no cargo build, no nptreemap runs)")
    ap.add_argument("--bin", type=Path, default=REPO / "target" / "release" / "nptreemap",
                    help="nptreemap binary (default target/release/nptreemap)")
    ap.add_argument("--no-build", action="store_true",
                    help="do not run `cargo build --release` first")
    ap.add_argument("--timeout", type=float, default=900.0,
                    help="seconds per nptreemap / check-layout process (default 900)")
    ap.add_argument("--layout-args", default="",
                    help="extra arguments for the `nptreemap layout` run that feeds "
                    "check-layout, e.g. \"--seed 1 --convergence 0.01\" (default none)")
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED,
                    help="the shared/ directory (default ../shared from the repo root)")
    args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error("--runs must be >= 1")
    if args.cases:
        names = [n.strip() for n in args.cases.split(",") if n.strip()]
        bad = [n for n in names if n not in ALL_CASES]
        if bad or not names:
            ap.error(f"unknown case(s) {', '.join(bad) or '(none)'}; "
                     f"choose from {', '.join(ALL_CASES)}")
    else:
        names = QUICK_SET if args.quick else FULL_SET
    args.case_list = [ALL_CASES[n] for n in names]
    args.shared = args.shared.resolve()
    if not (args.shared / "peers" / "gen.py").is_file():
        ap.error(f"{args.shared} does not look like shared/ (no peers/gen.py); use --shared")
    args.bin = args.bin.resolve()
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    cases = args.case_list
    env = {
        "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": machine_info(),
        "command": shlex.join(["python3", *sys.argv]) if argv is None
        else shlex.join(["python3", "benches/peers.py", *argv]),
        "node": node_version(),
        "git": git_revision(),
    }
    failed = False

    if not args.peer_only:
        if not args.no_build:
            err = build_ours()
            if err:
                log(f"ERROR: {err}")
                return 1
        if not os.access(args.bin, os.X_OK):
            log(f"ERROR: nptreemap binary {args.bin} not found or not executable")
            return 1
        env["ours"] = our_version(args.bin)

    inputs = generate_inputs(cases, args.shared)
    peer_err = install_peer(args.shared)
    if peer_err:
        log(f"d3 peer unavailable: {peer_err}")
    env["d3_version"] = peer_version()

    results = {}
    for c in cases:
        peer, ours = bench_case(c, inputs[c.name], args, args.shared, peer_err)
        results[c.name] = (peer, ours)
        if peer.versions and "d3_versions" not in env:
            env["d3_versions"] = peer.versions
            env["d3_version"] = peer.versions.get("d3-voronoi-treemap", env["d3_version"])
        failed |= ours.status == "error"

    env["machine"]["loadavg_end"] = machine_info()["loadavg"]
    report = render_report(cases, results, env, args)
    write_outputs(report, cases, results, env)
    sys.stdout.write(report)
    log(f"report written to {rel(BENCH_DIR / 'report.md')}"
        + ("; nptreemap had errors, exit 1" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
