#!/usr/bin/env python3
"""What a rebuild costs against a cold build (issue 22): the release binary's
`nptreemap build` on a C-headers-like tree, timed edit by edit in one run.

For each case it writes target/incremental/CASE/: the tree (benches/c_headers.py
over a real source tree, default /usr/include; `headers6000`, `headers2000` and
`headers500` keep 6,000, 2,000 and 500 of its headers, spread over the same
folders), a config with SVG, PNG, layout JSON and HTML outputs and
`limits.max_dimensions` raised to 10,000 (the tree has thousands of distinct
included names, each a dimension of the Jaccard vectors; the default limit is
1,024), then runs, each in a fresh process:

  cold          build --cold (no state folder yet)
  no-op         build again, nothing changed
  no-op check   build --check, nothing changed
  weight +10%   one header's size times 1.1: the first leaf (EGL/egl.h on
                /usr/include, most of its folder, so the edit moves the top
                level) and then the leaf of median size (a typical file)
  similarity    one header includes one more name (one similarity row)
  render        render.border_width changed in the config
  watch         `nptreemap -v watch`, one daemon: each of those headers'
                size times 1.1 again, the first leaf's then the median's,
                saved atomically; the time from the end of the batch of file
                events (the debounce) to the outputs on disk, as the daemon
                logs it with -v, and the wall time from the save to the
                status line (which includes the 100 ms debounce)

and prints wall and CPU time (user + system), peak RSS (os.wait4), their
ratios to the cold build (CPU time is the steadier figure on a shared
machine), how
the layout was got (the build's status line) and which stages ran (from
`-v`). Markdown on stdout and in target/incremental/report.md.

Usage (from the repository root):
    python3 benches/incremental.py                     # headers, headers2000, headers500
    python3 benches/incremental.py --cases headers500 --root /usr/include
    python3 benches/incremental.py --no-build --binary target/release/nptreemap

Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import datetime as dt
import queue
import signal
import threading
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "target" / "incremental"
CASES = {"headers": 0, "headers6000": 6000, "headers2000": 2000, "headers500": 500}

CONFIG = """# benches/incremental.py: a C-headers-like tree (benches/c_headers.py).
# limits.max_dimensions is raised: every distinct included name is a
# dimension of the Jaccard vectors.
limits: {{max_dimensions: 10000}}
render: {{border_width: {border}}}
datasets:
  - name: headers
    format: hierarchy-json
    files: {{hierarchy: tree.json}}
    outputs: [out/headers.svg, out/headers.png, out/headers.json, out/headers.html]
"""


def run_measured(binary: Path, args: list[str], cwd: Path) -> dict:
    """Runs the binary in `cwd`: wall time, exit code, output, and the
    child's peak RSS (os.wait4, so Popen must not reap it first)."""
    t = time.perf_counter()
    p = subprocess.Popen(
        [str(binary), *args],
        cwd=cwd,
        stdout=open(cwd / "stdout.txt", "w"),
        stderr=open(cwd / "stderr.txt", "w"),
    )
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t
    p.returncode = os.waitstatus_to_exitcode(status)
    return {
        "args": args,
        "wall_s": wall,
        "rss_mb": usage.ru_maxrss / 1024,
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "code": p.returncode,
        "stdout": (cwd / "stdout.txt").read_text(),
        "stderr": (cwd / "stderr.txt").read_text(),
    }


STAGE = re.compile(r"headers: (\w+)(?: (\S+))? (ran|reused) in ([0-9.]+) ms")


def stages(stderr: str) -> str:
    """The stages that ran, with their times: each output's render on its
    own (they run at once, so they do not add up), the writes as one (they
    are timed together)."""
    ran: dict[str, float] = {}
    for name, output, how, ms in STAGE.findall(stderr):
        if how != "ran":
            continue
        if name == "render" and output:
            key = f"render {output.rsplit('.', 1)[-1]}"
            ran[key] = ran.get(key, 0.0) + float(ms)
        elif name == "write":
            ran[name] = max(ran.get(name, 0.0), float(ms))
        else:
            ran[name] = ran.get(name, 0.0) + float(ms)
    return ", ".join(f"{k} {v / 1000:.2f} s" if v >= 100 else f"{k} {v:.0f} ms" for k, v in ran.items()) or "none"


def layout_line(stdout: str) -> str:
    for line in stdout.splitlines():
        if line.startswith("headers: "):
            return line[len("headers: "):].split(";")[0]
    return ""


ON_DISK = re.compile(r"headers: outputs on disk ([0-9.]+) ms after the batch \(data")


def watch_edits(binary: Path, folder: Path, tree: dict, leaves: list[dict]) -> list[dict]:
    """Starts `nptreemap -v watch`, waits for its start build, then for each
    of `leaves` saves one weight edit (+10%) atomically and waits (at most 10
    minutes) for the rebuild's status line, one daemon for all (the later
    edits find what the earlier renders kept, as in a session). Returns per
    edit the daemon's own figure (end of the batch to outputs on disk) and
    the wall time from the save to the line."""
    err = open(folder / "watch-stderr.txt", "w")
    p = subprocess.Popen(
        [str(binary), "-v", "watch", "nptreemap.yaml"],
        cwd=folder, stdout=subprocess.PIPE, stderr=err, text=True,
    )
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(l) for l in p.stdout], daemon=True).start()

    def wait_for(*words: str) -> str:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline:
            try:
                line = lines.get(timeout=1)
            except queue.Empty:
                continue
            if all(w in line for w in words):
                return line.strip()
        raise TimeoutError(f"no line with {words}")

    edits = []
    try:
        start = wait_for("headers: ", "start")
        for leaf in leaves:
            leaf["size"] = round(leaf["size"] * 1.1) + 1
            tmp = folder / ".tree.json.tmp"
            tmp.write_text(json.dumps(tree, separators=(",", ":")))
            t = time.perf_counter()
            os.replace(tmp, folder / "tree.json")
            line = wait_for("headers: ", "data: tree.json")
            edits.append({"start": start, "line": line, "wall_ms": (time.perf_counter() - t) * 1000})
            # Past the debounce, so the next save is a batch of its own.
            time.sleep(0.5)
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(timeout=30)
        err.close()
    stderr = (folder / "watch-stderr.txt").read_text()
    found = ON_DISK.findall(stderr)[-len(leaves):]
    # The stage lines of each edit's rebuild: between one "outputs on disk"
    # line and the next.
    parts = stderr.split("outputs on disk")[-len(leaves) - 1:-1]
    for k, e in enumerate(edits):
        e["on_disk_ms"] = float(found[k]) if k < len(found) else None
        e["stages"] = stages(parts[k]) if k < len(parts) else ""
    return edits


def first_leaf(node: dict) -> dict:
    while node.get("children"):
        node = node["children"][0]
    return node


def median_leaf(node: dict) -> dict:
    """The leaf of median size (ties by name) among those drawn at their own
    size: a typical file, where the first leaf of /usr/include (EGL/egl.h)
    is most of its folder. A file under 1:1000 of the heaviest entry of its
    folder (a file or a whole subfolder) is drawn at that floor
    (`min_weight_ratio`), and 10% more of it changes nothing."""
    def total(n: dict) -> float:
        if n.get("children"):
            n["_total"] = sum(total(c) for c in n["children"])
        else:
            n["_total"] = n.get("size", 0)
        return n["_total"]

    total(node)
    leaves, stack = [], [node]
    while stack:
        n = stack.pop()
        kids = n.get("children") or []
        heaviest = max((c["_total"] for c in kids), default=0)
        for c in kids:
            if c.get("children"):
                stack.append(c)
            elif c["_total"] >= heaviest / 1000:
                leaves.append(c)
    stack = [node]
    while stack:
        n = stack.pop()
        n.pop("_total", None)
        stack.extend(n.get("children") or [])
    leaves.sort(key=lambda n: (n.get("size", 0), n.get("name", "")))
    return leaves[len(leaves) // 2]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--root", default="/usr/include")
    ap.add_argument("--binary", default=str(REPO / "target" / "release" / "nptreemap"))
    ap.add_argument("--no-build", action="store_true")
    args = ap.parse_args()
    binary = Path(args.binary)
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=REPO, check=True)
    report = [
        f"`python3 benches/incremental.py --cases {args.cases} --root {args.root}`, "
        f"{dt.date.today()}, {platform.machine()} {os.cpu_count()} cores, {platform.platform()}",
        "",
    ]
    failed = False
    for case in args.cases.split(","):
        folder = OUT / case
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        gen = [sys.executable, str(REPO / "benches" / "c_headers.py"), str(folder / "tree.json"), "--root", args.root]
        if CASES[case]:
            gen += ["--leaves", str(CASES[case])]
        described = subprocess.run(gen, check=True, capture_output=True, text=True).stderr.strip()
        (folder / "nptreemap.yaml").write_text(CONFIG.format(border=2))
        steps = []

        def step(name: str, build_args: list[str]):
            r = run_measured(binary, ["-v", *build_args, "nptreemap.yaml"], folder)
            r["name"] = name
            steps.append(r)
            print(f"{case}: {name}: {r['wall_s']:.2f} s ({layout_line(r['stdout'])})", file=sys.stderr)
            return r

        step("cold", ["build", "--cold"])
        step("no-op build", ["build"])
        step("no-op build --check", ["build", "--check"])
        tree = json.loads((folder / "tree.json").read_text())
        leaf = first_leaf(tree)
        leaf["size"] = round(leaf["size"] * 1.1) + 1
        (folder / "tree.json").write_text(json.dumps(tree, separators=(",", ":")))
        step("one weight +10% (first leaf)", ["build"])
        median = median_leaf(tree)
        median["size"] = round(median["size"] * 1.1) + 1
        (folder / "tree.json").write_text(json.dumps(tree, separators=(",", ":")))
        step("one weight +10% (median leaf)", ["build"])
        features = leaf["embeddings"]
        if features and isinstance(features[0], str):
            # A set of included names: include one name more.
            features.append("one_more_included_name.h")
        else:
            k = features.index(0) if 0 in features else 0
            features[k] = 1 - features[k]
        (folder / "tree.json").write_text(json.dumps(tree, separators=(",", ":")))
        step("one similarity row", ["build"])
        (folder / "nptreemap.yaml").write_text(CONFIG.format(border=3))
        step("`render:` change", ["build"])

        watched, watched_median = watch_edits(binary, folder, tree, [leaf, median])
        print(f"{case}: watch: {watched['line']}", file=sys.stderr)
        print(f"{case}: watch (median leaf): {watched_median['line']}", file=sys.stderr)

        cold = steps[0]["wall_s"]
        cold_cpu = steps[0]["cpu_s"]
        report += [
            f"**{case}**: {described.split(': ', 1)[-1]}; "
            f"outputs {sum(f.stat().st_size for f in (folder / 'out').glob('headers.*')) / 1e6:.1f} MB, "
            f"state folder {sum(f.stat().st_size for f in (folder / 'out' / '.nptreemap').rglob('*') if f.is_file()) / 1e6:.1f} MB "
            f"(of which cache {sum(f.stat().st_size for f in (folder / 'out' / '.nptreemap' / 'cache').rglob('*') if f.is_file()) / 1e6:.1f} MB)",
            "",
            "| step | wall | CPU | peak RSS | wall / cold | CPU / cold | layout | stages that ran |",
            "|---|---:|---:|---:|---:|---:|---|---|",
        ]
        for s in steps:
            ok = s["code"] == 0
            failed |= not ok
            report.append(
                f"| {s['name']} | {s['wall_s']:.2f} s | {s['cpu_s']:.2f} s | {s['rss_mb']:.0f} MB | "
                f"{100 * s['wall_s'] / cold:.1f}% | {100 * s['cpu_s'] / cold_cpu:.1f}% | "
                f"{layout_line(s['stdout']) if ok else 'exit ' + str(s['code'])} | {stages(s['stderr'])} |"
            )
        report += [
            "",
        ]
        for what, w in (("first leaf", watched), ("median leaf", watched_median)):
            report += [
                f"`watch`, one weight +10% ({what}) saved atomically: outputs on disk "
                f"**{w['on_disk_ms']} ms** after the end of the batch (the daemon's -v figure); "
                f"{w['wall_ms']:.0f} ms from the save to the status line (debounce included); "
                f"stages that ran: {w['stages']}; line: `{w['line']}`",
                "",
            ]
        (folder / "steps.json").write_text(
            json.dumps({"steps": steps, "watch": watched, "watch_median": watched_median}, indent=1)
        )
    text = "\n".join(report)
    print(text)
    (OUT / "report.md").write_text(text + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
