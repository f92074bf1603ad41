#!/usr/bin/env python3
"""`nptreemap watch` under edits (issue 6 acceptance).

Two runs on a 500-leaf hierarchy with embeddings (benches/gen_similar.py;
default method `neighbor`, outputs SVG, PNG and layout JSON at 1000 x 1000):

  latency  one leaf's weight is edited --edits times (10% up), each after the
           daemon went quiet. For each edit it records the daemon's own figure
           (its status line: read + parse + warm layout + render + write, from
           the moment the batch closed) and, from outside, the time from the
           write of the data file to the moment the new JSON is in place, minus
           the 100 ms quiet window. A cold layout of the same data
           (`nptreemap bench --cold`) gives the warm/cold ratio.
  stress   --stress edits (default 1,000) within --seconds (default 60), each a
           random leaf's weight, written atomically (temp file + rename) or in
           place, alternating; the daemon's resident memory is sampled every
           second. At the end the outputs must hold every weight of the last
           edit and pass shared/tools/check-layout.

Prints a Markdown report for BENCHMARKS.md.

usage: python3 benches/watch.py [--bin PATH] [--no-build] [--leaves 500]
       [--edits 10] [--stress 1000] [--seconds 60]
Python 3 standard library only; needs cargo unless --no-build.
"""
import argparse
import datetime as dt
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT / ".." / "shared"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from peers import git_revision, machine_info  # noqa: E402

CONFIG = """datasets:
  - name: bench
    format: hierarchy-json
    files: {hierarchy: data/tree.json}
    outputs:
      - path: out/bench.svg
      - path: out/bench.png
      - path: out/bench.json
"""
QUIET_MS = 100


def leaves(node, out):
    kids = node.get("children") or []
    if not kids:
        out.append(node)
    for k in kids:
        leaves(k, out)
    return out


def weight_key(tree):
    return tree.get("weightAttribute") or "value"


class Daemon:
    """nptreemap watch in the background; status lines go to a queue."""

    def __init__(self, binary, config):
        self.proc = subprocess.Popen([binary, "watch", str(config)], stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True)
        self.lines = []
        self.cond = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            with self.cond:
                self.lines.append((time.monotonic(), line.rstrip("\n")))
                self.cond.notify_all()

    def wait_for(self, pred, start_index, timeout=120):
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                for i in range(start_index, len(self.lines)):
                    if pred(self.lines[i][1]):
                        return i
                left = deadline - time.monotonic()
                if left <= 0:
                    raise SystemExit("timed out; lines:\n" + "\n".join(l for _, l in self.lines))
                self.cond.wait(left)

    def rss_kib(self):
        with open(f"/proc/{self.proc.pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        return 0

    def stop(self):
        self.proc.terminate()
        return self.proc.wait(timeout=30)


def status_ms(line):
    # "bench: data: tree.json; laid out warm in 9 ms, on disk in 41 ms; wrote ..."
    # or "bench: config: render; re-rendered in 41 ms; ...": the last time
    # before the outputs, the whole rebuild's.
    head = line.split("; wrote", 1)[0].split("; no output", 1)[0]
    part = head.rsplit(" in ", 1)[1]
    return float(part.split(" ms", 1)[0])


def write(path, text, atomic):
    if atomic:
        tmp = path.with_name("." + path.name + ".tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
    else:
        path.write_text(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=str(ROOT / "target" / "release" / "nptreemap"))
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--leaves", type=int, default=500)
    ap.add_argument("--edits", type=int, default=10)
    ap.add_argument("--stress", type=int, default=1000)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)

    tmp = Path(tempfile.mkdtemp(prefix="nptreemap-watch-bench-"))
    (tmp / "data").mkdir()
    tree_path = tmp / "data" / "tree.json"
    subprocess.run([sys.executable, str(ROOT / "benches" / "gen_similar.py"), "--n", str(args.leaves),
                    "--depth", "3", "--dim", "32", "--seed", "1", "--out", str(tree_path)], check=True)
    tree = json.loads(tree_path.read_text())
    key = weight_key(tree)
    config = tmp / "nptreemap.yaml"
    config.write_text(CONFIG)
    out_json = tmp / "out" / "bench.json"

    # Cold reference: the same layout step from scratch.
    cold = json.loads(subprocess.run([args.bin, "bench", str(tree_path), "--repeat", "3"],
                                     capture_output=True, text=True, check=True).stdout)
    daemon = Daemon(args.bin, config)
    daemon.wait_for(lambda l: l.startswith("bench: start"), 0)

    # --- latency --------------------------------------------------------------
    ls = leaves(tree, [])
    rng = random.Random(1)
    own, outside = [], []
    for e in range(args.edits):
        leaf = ls[rng.randrange(len(ls))]
        leaf[key] = float(leaf[key]) * 1.1
        mark = len(daemon.lines)
        before = out_json.stat().st_mtime_ns
        t0 = time.monotonic()
        write(tree_path, json.dumps(tree), atomic=False)
        i = daemon.wait_for(lambda l: l.startswith("bench: data:"), mark)
        while out_json.stat().st_mtime_ns == before:
            time.sleep(0.001)
        t1 = daemon.lines[i][0]
        own.append(status_ms(daemon.lines[i][1]))
        outside.append((t1 - t0) * 1000.0 - QUIET_MS)
        time.sleep(0.3)

    # --- stress ---------------------------------------------------------------
    rss = [daemon.rss_kib()]
    stop_sampling = threading.Event()

    def sample():
        while not stop_sampling.wait(1.0):
            rss.append(daemon.rss_kib())

    threading.Thread(target=sample, daemon=True).start()
    interval = args.seconds / max(args.stress, 1)
    t_start = time.monotonic()
    for e in range(args.stress):
        leaf = ls[rng.randrange(len(ls))]
        leaf[key] = round(max(1.0, float(leaf[key]) * rng.uniform(0.8, 1.25)), 3)
        write(tree_path, json.dumps(tree), atomic=(e % 2 == 0))
        next_at = t_start + (e + 1) * interval
        time.sleep(max(0.0, next_at - time.monotonic()))
    edits_s = time.monotonic() - t_start
    want = {l["id"]: float(l[key]) for l in ls}
    deadline = time.monotonic() + 120
    while True:
        try:
            got = json.loads(out_json.read_text())
            have = {n["id"]: n["weight"] for n in got["nodes"] if n["id"] in want}
            if all(abs(have.get(i, -1) - w) <= 1e-6 * max(1.0, w) for i, w in want.items()):
                break
        except (ValueError, KeyError):
            pass
        if time.monotonic() > deadline:
            raise SystemExit("final outputs never matched the final data")
        time.sleep(0.2)
    stop_sampling.set()
    time.sleep(1.1)
    alive = daemon.proc.poll() is None
    check = subprocess.run([sys.executable, str(SHARED / "tools" / "check-layout"), str(out_json)],
                           capture_output=True, text=True)
    rebuilds = sum(1 for _, l in daemon.lines if l.startswith("bench: data:"))
    errors = [l for _, l in daemon.lines if "error" in l]
    for e in errors[:3]:
        print("error line:", e[:300], file=sys.stderr)
    code = daemon.stop()

    print("rss samples (MiB):", " ".join(f"{r / 1024:.0f}" for r in rss), file=sys.stderr)
    print(f"## `nptreemap watch` ({dt.date.today()}, revision {git_revision()})\n")
    machine = ", ".join(f"{k} {v}" for k, v in machine_info().items())
    print(f"Machine: {machine}. Command: `python3 benches/watch.py` "
          f"({args.leaves} leaves with 32-d embeddings, method neighbor, SVG + PNG + JSON at 1000 x 1000).\n")
    med_own, med_out = statistics.median(own), statistics.median(outside)
    print("| one-leaf weight edit (10%) | median | max |")
    print("|---|--:|--:|")
    print(f"| daemon's own time (batch closed -> outputs written) | {med_own:.0f} ms | {max(own):.0f} ms |")
    print(f"| file written -> new JSON in place, minus the 100 ms window | {med_out:.0f} ms | {max(outside):.0f} ms |")
    print(f"\nCold layout of the same data (`nptreemap bench --cold`): {cold['time_ms']:.0f} ms; "
          f"the whole warm rebuild (layout + render + write) is {cold['time_ms'] / med_own:.1f}x faster "
          f"than the cold layout step alone.\n")
    print(f"Stress: {args.stress} edits in {edits_s:.1f} s -> {rebuilds} rebuilds (batched), "
          f"daemon alive: {alive}, exit code after SIGTERM: {code}, errors: {len(errors)}; "
          f"final outputs hold every final weight; check-layout: {'ok' if check.returncode == 0 else 'FAILED'}.")
    # Samples taken during a rebuild catch its transient peak (pixmaps, parse
    # trees); a leak shows as a rising level between rebuilds, so compare the
    # typical level of the first and last quarter of the run.
    q = max(1, len(rss) // 4)
    level_first, level_last = statistics.median(rss[:q]), statistics.median(rss[-q:])
    drift = 100.0 * (level_last - level_first) / max(level_first, 1)
    print(f"Resident memory: typical level {level_first / 1024:.1f} MiB in the first quarter of the run, "
          f"{level_last / 1024:.1f} MiB in the last ({drift:+.1f}%); peaks during rebuilds up to "
          f"{max(rss) / 1024:.1f} MiB ({len(rss)} samples, one per second).")
    ok = alive and code == 0 and check.returncode == 0 and not errors
    print("\nAcceptance: within 150 ms after the window:",
          "yes" if med_out <= 150 else "NO", "| warm >= 3x faster than cold:",
          "yes" if cold["time_ms"] / med_own >= 3 else "NO", "| stress clean:", "yes" if ok else "NO",
          "| memory flat within 10%:", "yes" if abs(drift) <= 10 else "NO")


if __name__ == "__main__":
    main()
