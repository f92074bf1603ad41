#!/usr/bin/env python3
"""Layout quality and time of nptreemap on the real-data corpus, per seed and method.

Owns the measurement of the datasets that benches/realdata/make.py writes (and
of the snapshot in tests/data/real/): for every config (a folder's *.yaml, or
the files named), every dataset in it, every seed and every method it runs the
release binary once and reads the layout JSON it wrote:

- `nptreemap eval --config FILE --dataset NAME --seed S --method M` when the
  binary's `eval` has `--config` (it does not yet); else
- `nptreemap build --cold TMP.yaml`, where TMP.yaml is a JSON copy of the
  config (YAML is a superset of JSON) holding that one dataset, its input paths
  made absolute, `layout: {seed: S, method: M}` added and one `.json` output in
  a temporary folder (`--keep DIR` keeps the outputs, and a `.png` for the first
  seed). One dataset per run: a failing dataset would stop the build of the
  others in its config.

Per run it reports whether it failed (exit status and the error line), the wall
time of the process, the realised leaf constraints (the layout JSON's
`constraints` between nodes of the deepest level, `realized` flags), the mean
leaf bounding-box aspect ratio (long side / short side of each leaf polygon's
bounding box), the area error (mean |cell area / parent area - weight / parent
weight| over non-root nodes), and the same figures as
../shared/tools/check-layout recomputes them (`aspect_ratio_mean`,
`area_error_share_mean`, `area_error_diagram_mean`, and whether it passed).
Prints Markdown: a summary per dataset and method, then every run.

When one run of a dataset and method takes longer than --cap-seconds (default
180), its remaining seeds are skipped and the table says so.

Only the Python standard library is used.

usage: measure.py [CONFIG_OR_FOLDER ...] [--seeds 1-5] [--methods plain,neighbor]
                  [--bin target/release/nptreemap] [--json FILE] [--keep DIR]
       measure.py --from-json FILE      # the tables of an earlier run
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
CHECKER = REPO.parent / "shared" / "tools" / "check-layout"


# ------------------------------------------------------- a small YAML reader


def _strip_comment(line):
    """The line without a trailing `# comment` outside quotes."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1] in " \t"):
            return line[:i].rstrip()
    return line.rstrip()


def _split_flow(text):
    """Splits `a, b, {c: d}` at top-level commas."""
    parts, depth, quote, cur = [], 0, None, ""
    for ch in text:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
            continue
        cur += ch
    if cur.strip():
        parts.append(cur.strip())
    return parts


def _scalar(text):
    """A YAML scalar or flow collection of the subset the configs use."""
    t = text.strip()
    if t.startswith("[") and t.endswith("]"):
        return [_scalar(p) for p in _split_flow(t[1:-1])]
    if t.startswith("{") and t.endswith("}"):
        out = {}
        for p in _split_flow(t[1:-1]):
            k, _, v = p.partition(":")
            out[_scalar(k)] = _scalar(v)
        return out
    if t.startswith('"') and t.endswith('"') and len(t) >= 2:
        return json.loads(t)
    if t.startswith("'") and t.endswith("'") and len(t) >= 2:
        return t[1:-1].replace("''", "'")
    if t in ("", "null", "~"):
        return None
    if t in ("true", "false"):
        return t == "true"
    if re.fullmatch(r"[-+]?\d+", t):
        return int(t)
    if re.fullmatch(r"[-+]?(\d+\.\d*|\.\d+|\d+)([eE][-+]?\d+)?", t):
        return float(t)
    return t


def _key_value(text):
    """(key, rest) when `text` is `key: rest` or `key:`, else None."""
    m = re.match(r"^([^\s\"'#:][^:]*?|\"[^\"]*\"|'[^']*'):(\s+|$)(.*)$", text)
    return (_scalar(m.group(1)), m.group(3)) if m else None


def parse_yaml(text):
    """Block mappings and sequences with scalar / flow values (the config subset)."""
    lines = []
    for raw in text.splitlines():
        line = _strip_comment(raw)
        if line.strip():
            lines.append((len(line) - len(line.lstrip(" ")), line.strip()))

    def block(i, indent):
        if i >= len(lines):
            return None, i
        if lines[i][1].startswith("- ") or lines[i][1] == "-":
            seq = []
            while i < len(lines) and lines[i][0] == indent and (lines[i][1].startswith("- ") or lines[i][1] == "-"):
                rest = lines[i][1][2:].strip()
                if not rest:
                    val, i = block(i + 1, lines[i + 1][0]) if i + 1 < len(lines) and lines[i + 1][0] > indent else (None, i + 1)
                    seq.append(val)
                    continue
                if _key_value(rest) and not rest.startswith(("[", "{", '"')):
                    # `- key: value` opens a mapping whose keys sit at indent + 2
                    lines[i] = (indent + 2, rest)
                    val, i = block(i, indent + 2)
                    seq.append(val)
                else:
                    seq.append(_scalar(rest))
                    i += 1
            return seq, i
        mapping = {}
        while i < len(lines) and lines[i][0] == indent and not lines[i][1].startswith("- "):
            kv = _key_value(lines[i][1])
            if kv is None:
                raise ValueError(f"cannot read line: {lines[i][1]!r}")
            key, rest = kv
            if rest.strip():
                mapping[key] = _scalar(rest)
                i += 1
            elif i + 1 < len(lines) and (lines[i + 1][0] > indent or
                                         (lines[i + 1][0] == indent and lines[i + 1][1].startswith("- "))):
                mapping[key], i = block(i + 1, lines[i + 1][0])
            else:
                mapping[key] = None
                i += 1
        return mapping, i

    value, _ = block(0, lines[0][0]) if lines else ({}, 0)
    return value


# ------------------------------------------------------- figures from a layout


def layout_figures(path):
    """Leaf constraints, leaf aspect ratio and area error from a layout JSON."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    nodes = {n["id"]: n for n in doc["nodes"]}
    parents = {n["parent"] for n in doc["nodes"] if n["parent"] is not None}
    deepest = max(n["depth"] for n in doc["nodes"])
    leaf_cons = [c for c in doc.get("constraints", [])
                 if nodes[c["a"]]["depth"] == deepest and nodes[c["b"]]["depth"] == deepest]

    def area(poly):
        s = 0.0
        for (x1, y1), (x2, y2) in zip(poly, poly[1:] + poly[:1]):
            s += x1 * y2 - x2 * y1
        return abs(s) / 2

    aspects = []
    for n in doc["nodes"]:
        if n["id"] in parents:
            continue
        xs = [p[0] for p in n["polygon"]]
        ys = [p[1] for p in n["polygon"]]
        w, h = max(xs) - min(xs), max(ys) - min(ys)
        aspects.append(max(w, h) / min(w, h) if min(w, h) > 0 else float("inf"))
    errors = []
    for n in doc["nodes"]:
        p = nodes.get(n["parent"]) if n["parent"] is not None else None
        if p is None or not p["weight"]:
            continue
        errors.append(abs(area(n["polygon"]) / area(p["polygon"]) - n["weight"] / p["weight"]))
    return {
        "leaves": len(aspects),
        "levels": deepest,
        "leaf_constraints": len(leaf_cons),
        "leaf_realized": sum(1 for c in leaf_cons if c["realized"]),
        "aspect_mean": statistics.fmean(aspects) if aspects else None,
        "area_error_mean": statistics.fmean(errors) if errors else None,
        "area_error_max": max(errors) if errors else None,
    }


def check_layout(path, timeout):
    """check-layout's report (None when the checker is missing or fails to run)."""
    if not CHECKER.exists():
        return None
    try:
        p = subprocess.run([sys.executable, str(CHECKER), str(path)], capture_output=True,
                           text=True, timeout=timeout)
        return json.loads(p.stdout)
    except (subprocess.TimeoutExpired, json.JSONDecodeError):
        return None


# ------------------------------------------------------- runs


def datasets_of(config_path):
    """The config's parsed text and its datasets."""
    cfg = parse_yaml(Path(config_path).read_text(encoding="utf-8")) or {}
    return cfg, cfg.get("datasets") or []


def eval_has_config(binary):
    """Whether `nptreemap eval` takes --config (the planned config-driven eval)."""
    p = subprocess.run([binary, "eval", "--help"], capture_output=True, text=True)
    return "--config" in p.stdout


def error_line(stderr):
    """The most telling line of a failed run's stderr."""
    # Paths relative to the working folder, so tables do not carry this machine's layout.
    stderr = stderr.replace(str(Path.cwd()) + os.sep, "")
    lines = [l.strip() for l in stderr.splitlines() if l.strip()]
    for l in lines:
        if "error" in l.lower():
            return l
    return lines[-1] if lines else ""


def run_once(binary, config_path, cfg, ds, seed, method, workdir, use_eval, timeout, png):
    """One layout of one dataset: returns the row of the per-run table."""
    base = Path(config_path).resolve().parent
    out_json = workdir / f"{ds['name']}.json"
    if out_json.exists():
        out_json.unlink()
    if use_eval:
        cmd = [binary, "eval", "--config", str(config_path), "--dataset", ds["name"], "--seed", str(seed),
               "--method", method, "--json", "--out", str(out_json)]
    else:
        layout = dict(cfg.get("layout") or {})
        layout.update({"seed": seed, "method": method})
        entry = dict(ds)
        entry["files"] = {role: str((base / f).resolve()) for role, f in (ds.get("files") or {}).items()}
        entry["outputs"] = [{"path": str(out_json)}]
        if png:
            entry["outputs"].append({"path": str(workdir / f"{ds['name']}.png")})
        tmp_cfg = {"layout": layout, "datasets": [entry]}
        if cfg.get("render"):
            tmp_cfg["render"] = cfg["render"]
        cfg_path = workdir / "measure.yaml"
        cfg_path.write_text(json.dumps(tmp_cfg, indent=1) + "\n", encoding="utf-8")
        cmd = [binary, "build", "--cold", str(cfg_path)]
    row = {"config": str(config_path), "dataset": ds["name"], "seed": seed, "method": method,
           "command": "eval" if use_eval else "build"}
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        rc, stderr, stdout = p.returncode, p.stderr, p.stdout
    except subprocess.TimeoutExpired:
        rc, stderr, stdout = None, f"timed out after {timeout} s", ""
    row["seconds"] = round(time.monotonic() - t0, 2)
    row["exit"] = rc
    if use_eval and stdout.strip().startswith("{"):
        try:
            row["eval"] = json.loads(stdout)
        except json.JSONDecodeError:
            pass
    if rc != 0 or not out_json.exists():
        row["error"] = error_line(stderr) or f"exit status {rc}, no layout written"
        return row
    row.update(layout_figures(out_json))
    chk = check_layout(out_json, timeout)
    if chk is not None:
        row["check"] = {k: chk.get(k) for k in ("ok", "aspect_ratio_mean", "area_error_share_mean",
                                                "area_error_share_max", "area_error_diagram_mean",
                                                "realized_lowest", "constraints_lowest", "problem_count")}
    return row


def parse_seeds(text):
    """`1-5` or `1,3,7` -> list of ints."""
    out = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out.extend(range(int(a), int(b) + 1) if b else [int(a)])
    return out


# ------------------------------------------------------- tables


def pct(row):
    """`realised/total (p %)` of a row's leaf constraints."""
    if not row.get("leaf_constraints"):
        return "0/0"
    return f"{row['leaf_realized']}/{row['leaf_constraints']} ({100 * row['leaf_realized'] / row['leaf_constraints']:.1f} %)"


def num(x, digits=3):
    return "–" if x is None else f"{x:.{digits}f}"


def sci(x):
    return "–" if x is None else f"{x:.1e}"


def run_table(rows):
    """Every run, one line each."""
    out = ["| dataset | method | seed | result | time s | leaf constraints realised | aspect mean | area err mean | "
           "check-layout: ok, aspect mean, area err share mean, diagram mean |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.get("skipped"):
            out.append(f"| {r['dataset']} | {r['method']} | {r['seed']} | skipped ({r['skipped']}) | | | | | |")
            continue
        if "error" in r:
            out.append(f"| {r['dataset']} | {r['method']} | {r['seed']} | **failed**: {r['error'].replace('|', '/')} | "
                       f"{r['seconds']:.1f} | | | | |")
            continue
        c = r.get("check") or {}
        chk = (f"{'ok' if c.get('ok') else 'FAIL'}, {num(c.get('aspect_ratio_mean'))}, "
               f"{sci(c.get('area_error_share_mean'))}, {sci(c.get('area_error_diagram_mean'))}") if c else "–"
        out.append(f"| {r['dataset']} | {r['method']} | {r['seed']} | ok | {r['seconds']:.1f} | {pct(r)} | "
                   f"{num(r['aspect_mean'])} | {sci(r['area_error_mean'])} | {chk} |")
    return "\n".join(out)


def summary_table(rows):
    """Per dataset and method: runs, failures, median time, realised share range."""
    out = ["| dataset | leaves | method | runs ok / failed / skipped | median time s (all runs) | leaf constraints | "
           "realised % mean (min–max) | aspect mean | area err mean | check-layout ok |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    keys = []
    for r in rows:
        k = (r["dataset"], r["method"])
        if k not in keys:
            keys.append(k)
    for k in keys:
        rs = [r for r in rows if (r["dataset"], r["method"]) == k]
        ok = [r for r in rs if not r.get("skipped") and "error" not in r]
        bad = [r for r in rs if "error" in r]
        skipped = [r for r in rs if r.get("skipped")]
        times = [r["seconds"] for r in rs if not r.get("skipped")]
        if ok:
            shares = [100 * r["leaf_realized"] / r["leaf_constraints"] if r["leaf_constraints"] else 0 for r in ok]
            checks = [r.get("check") or {} for r in ok]
            out.append(
                f"| {k[0]} | {ok[0]['leaves']} | {k[1]} | {len(ok)} / {len(bad)} / {len(skipped)} | "
                f"{statistics.median(times):.1f} | {ok[0]['leaf_constraints']} | "
                f"{statistics.fmean(shares):.1f} ({min(shares):.1f}–{max(shares):.1f}) | "
                f"{statistics.fmean(r['aspect_mean'] for r in ok):.2f} | "
                f"{sci(statistics.fmean(r['area_error_mean'] for r in ok))} | "
                f"{sum(1 for c in checks if c.get('ok'))}/{len(ok)} |")
        else:
            err = bad[0]["error"].replace("|", "/") if bad else ""
            out.append(f"| {k[0]} | – | {k[1]} | 0 / {len(bad)} / {len(skipped)} | "
                       f"{statistics.median(times):.1f} | – | **failed**: {err} | | | |" if times else
                       f"| {k[0]} | – | {k[1]} | 0 / 0 / {len(skipped)} | | | | | | |")
    return "\n".join(out)


def find_configs(paths):
    """Config files: the files named, and every *.yaml in the folders named (sorted)."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            direct = sorted(p.glob("*.yaml"))
            out.extend(direct if direct else sorted(p.glob("*/*.yaml")))
        else:
            out.append(p)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("paths", nargs="*", default=["target/realdata"],
                    help="configs or folders (a folder's *.yaml, else its subfolders'); default target/realdata")
    ap.add_argument("--bin", default=str(REPO / "target" / "release" / "nptreemap"))
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--methods", default="plain,neighbor")
    ap.add_argument("--only", default="", help="comma-separated dataset names")
    ap.add_argument("--timeout", type=int, default=900, help="seconds before one run is stopped")
    ap.add_argument("--cap-seconds", type=float, default=180,
                    help="after a run slower than this, skip the dataset's remaining seeds for that method")
    ap.add_argument("--json", help="write every run's figures to this file")
    ap.add_argument("--keep", help="keep each run's outputs (and a PNG of the first seed) under this folder")
    ap.add_argument("--from-json", help="print the tables of an earlier --json file instead of running")
    args = ap.parse_args()
    if args.from_json:
        rows = json.loads(Path(args.from_json).read_text(encoding="utf-8"))
        print(f"Runs from {args.from_json}.\n\n### Summary\n\n{summary_table(rows)}\n\n### Every run\n\n{run_table(rows)}")
        return 0
    if not Path(args.bin).exists():
        ap.error(f"{args.bin} not found: cargo build --release first")
    seeds = parse_seeds(args.seeds)
    methods = [m for m in args.methods.split(",") if m]
    only = {n for n in args.only.split(",") if n}
    use_eval = eval_has_config(args.bin)
    rows = []
    for config in find_configs(args.paths):
        cfg, datasets = datasets_of(config)
        for ds in datasets:
            if only and ds["name"] not in only:
                continue
            for method in methods:
                capped = None
                for seed in seeds:
                    if capped:
                        rows.append({"dataset": ds["name"], "method": method, "seed": seed, "skipped": capped})
                        continue
                    if args.keep:
                        workdir = Path(args.keep).resolve() / f"{ds['name']}-{method}-{seed}"
                        workdir.mkdir(parents=True, exist_ok=True)
                        cleanup = False
                    else:
                        workdir = Path(tempfile.mkdtemp(prefix="nptreemap-measure-"))
                        cleanup = True
                    try:
                        row = run_once(args.bin, config, cfg, ds, seed, method, workdir, use_eval, args.timeout,
                                       png=bool(args.keep) and seed == seeds[0])
                    finally:
                        if cleanup:
                            shutil.rmtree(workdir, ignore_errors=True)
                    rows.append(row)
                    state = row.get("error") or f"{pct(row)}, aspect {num(row.get('aspect_mean'))}"
                    print(f"{ds['name']} {method} seed {seed}: {row['seconds']:.1f} s, {state}", file=sys.stderr)
                    if row["seconds"] > args.cap_seconds:
                        capped = f"seed {seed} took {row['seconds']:.0f} s > {args.cap_seconds:.0f} s"
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    mode = "eval --config" if use_eval else "build --cold on a one-dataset copy of the config"
    print(f"Runs: `{mode}`, seeds {args.seeds}, methods {args.methods}.\n")
    print("### Summary\n")
    print(summary_table(rows))
    print("\n### Every run\n")
    print(run_table(rows))
    return 1 if any("error" in r for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
