#!/usr/bin/env python3
"""The live preview's latency in a real browser (issue 32): from the outputs
on disk to the edited cell's new outline on screen.

For each size, a hierarchy with embeddings (benches/gen_similar.py, three
levels, 32-d, seed 1; outputs SVG, PNG, layout JSON and HTML) is watched by
`nptreemap watch --serve`, its page opened in headless Chromium (1280 x 900)
over the DevTools protocol (benches/page.py's client), and one leaf's weight
edited (+10%) --edits times, each after the page went quiet. Per edit:

- `first`: the daemon's status line (the outputs are on disk) to the first
  change of the edited cell's outline in the page (a MutationObserver on its
  `d`): the first frame of the morph;
- `done`: the same line to the page's update counter moving (the morph
  ended, the map whole again); with prefers-reduced-motion emulated, the
  change is drawn at once, and `done` is the whole latency;
- how the page updated: patched in place (`npLive.patches`, with the number
  of cells patched) or fetched whole (`npLive.loads`);
- `--whole` runs the same edits with the patch turned off (the page fetches
  itself whole, as before issue 32), for the ratio in one run.

Clocks: the daemon's line is stamped when this script reads it, the page's
events with `performance.timeOrigin + performance.now()`; both are this
machine's wall clock. Not a test: it prints a Markdown table.

    python3 benches/live.py [--bin target/release/nptreemap] [--sizes 500,20000]
        [--edits 3] [--whole]
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from page import Browser  # noqa: E402
from peers import git_revision, machine_info  # noqa: E402
from watch import leaves  # noqa: E402

CONFIG = """datasets:
  - name: bench
    format: hierarchy-json
    files: {hierarchy: data/tree.json}
    outputs: [out/bench.svg, out/bench.png, out/bench.json, out/bench.html]
"""

# The edited cell's outline and the update counter, stamped on the wall clock.
PROBE = """(function (id) {
  window.__t = { first: 0, done: 0 };
  var now = function () { return performance.timeOrigin + performance.now(); };
  var svg = document.querySelector('.nptreemap .np-map > svg:not(.np-hover)');
  new MutationObserver(function (rs) {
    rs.forEach(function (r) {
      if (!__t.first && r.target.getAttribute && r.target.getAttribute('data-id') === id) { __t.first = now(); }
    });
  }).observe(document.body, { attributes: true, subtree: true, attributeFilter: ['d'] });
  new MutationObserver(function () { __t.done = now(); })
    .observe(document.documentElement, { attributes: true, attributeFilter: ['data-np-live-updates'] });
  return !!svg;
})(%s)"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Daemon:
    """`nptreemap watch --serve`; its status lines, stamped on arrival."""

    def __init__(self, binary: str, config: Path, port: int):
        self.proc = subprocess.Popen([binary, "watch", str(config), "--serve", f"127.0.0.1:{port}"],
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.lines: list = []
        self.cond = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            with self.cond:
                self.lines.append((time.time() * 1000.0, line.rstrip("\n")))
                self.cond.notify_all()

    def wait_for(self, prefix: str, start: int, timeout: float = 600.0):
        deadline = time.monotonic() + timeout
        with self.cond:
            while True:
                for i in range(start, len(self.lines)):
                    # Lines start with the time of day ("02:01:00 bench: ...").
                    text = self.lines[i][1].split(" ", 1)[-1]
                    if text.startswith(prefix):
                        return self.lines[i]
                left = deadline - time.monotonic()
                if left <= 0:
                    raise SystemExit("timed out; lines:\n" + "\n".join(l for _, l in self.lines))
                self.cond.wait(left)

    def stop(self):
        self.proc.terminate()
        self.proc.wait(timeout=30)


def run_size(args, n: int, whole: bool) -> dict:
    tmp = Path(tempfile.mkdtemp(prefix="nptreemap-live-bench-"))
    (tmp / "data").mkdir()
    tree_path = tmp / "data" / "tree.json"
    subprocess.run([sys.executable, str(ROOT / "benches" / "gen_similar.py"), "--n", str(n),
                    "--depth", "3", "--dim", "32", "--seed", "1", "--out", str(tree_path)], check=True)
    tree = json.loads(tree_path.read_text())
    key = tree.get("weightAttribute") or "value"
    (tmp / "nptreemap.yaml").write_text(CONFIG)
    port = free_port()
    daemon = Daemon(args.bin, tmp / "nptreemap.yaml", port)
    browser = Browser(args.chromium)
    rows = []
    try:
        daemon.wait_for("bench: start", 0)
        browser.viewport(1280, 900)
        browser.open(f"http://127.0.0.1:{port}/out/bench.html")
        browser.wait("(document.querySelector('.np-live-status') || {}).textContent === 'live: following bench'",
                     "the event stream", 120)
        if whole:
            browser.eval("npLive.whole = true")
        ls = leaves(tree, [])
        # The heaviest leaf: its cell is drawn large enough to see move.
        leaf = max(ls, key=lambda l: float(l[key]))
        for e in range(args.edits * 2):
            reduced = e >= args.edits
            browser.call("Emulation.setEmulatedMedia", {"features": [
                {"name": "prefers-reduced-motion", "value": "reduce" if reduced else "no-preference"}]})
            browser.eval(PROBE % json.dumps(leaf["id"]))
            counts = browser.eval("[npLive.updates, npLive.patches, npLive.loads]")
            leaf[key] = float(leaf[key]) * 1.1
            mark = len(daemon.lines)
            tree_path.write_text(json.dumps(tree))
            t_disk, line = daemon.wait_for("bench: data:", mark)
            browser.wait(f"npLive.updates > {counts[0]} && npLive.animating === 0 && __t.done > 0",
                         "the page to update", 600)
            t = browser.eval("[__t.first, __t.done, npLive.patches, npLive.loads, npLive.patched]")
            rows.append({
                "reduced": reduced,
                "first": t[0] - t_disk if t[0] else None,
                "done": t[1] - t_disk,
                "patched": t[2] > counts[1],
                "loaded": t[3] > counts[2],
                "cells": t[4],
                "daemon": line,
            })
            time.sleep(0.5)
    finally:
        browser.close()
        daemon.stop()
    return {"n": n, "whole": whole, "rows": rows}


def med(values):
    values = [v for v in values if v is not None]
    return f"{statistics.median(values):.0f} ms" if values else "-"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=str(ROOT / "target" / "release" / "nptreemap"))
    ap.add_argument("--chromium", default="chromium")
    ap.add_argument("--sizes", default="500,20000")
    ap.add_argument("--edits", type=int, default=3)
    ap.add_argument("--whole", action="store_true", help="also run with the patch turned off")
    args = ap.parse_args()
    results = []
    for n in [int(s) for s in args.sizes.split(",")]:
        for whole in ([False, True] if args.whole else [False]):
            r = run_size(args, n, whole)
            results.append(r)
            for row in r["rows"]:
                print(json.dumps({"n": n, "whole": whole, **row}), file=sys.stderr)
    print(f"## The live preview's latency ({dt.date.today()}, revision {git_revision()})\n")
    machine = ", ".join(f"{k} {v}" for k, v in machine_info().items())
    print(f"Machine: {machine}. Command: `python3 benches/live.py --sizes {args.sizes} --edits {args.edits}"
          f"{' --whole' if args.whole else ''}` (medians of {args.edits} edits each).\n")
    print("| leaves | page update | how | outputs on disk → first frame | → morph ended | "
          "reduced motion: → drawn |")
    print("|--:|---|---|--:|--:|--:|")
    for r in results:
        moving = [x for x in r["rows"] if not x["reduced"]]
        still = [x for x in r["rows"] if x["reduced"]]
        how = ", ".join(sorted({("patch (%d cells)" % x["cells"]) if x["patched"] else "whole page"
                                for x in r["rows"]}))
        print(f"| {r['n']:,} | {'whole page (patch off)' if r['whole'] else 'patch'} | {how} | "
              f"{med([x['first'] for x in moving])} | {med([x['done'] for x in moving])} | "
              f"{med([x['done'] for x in still])} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
