#!/usr/bin/env python3
"""Colours that stay (issue 32, item 4): fills changed by weight edits on
tables of 6, 30 and 120 groups, and how far apart the legend's colours are.

For each group count it writes target/colors/gG/ (a genre table of
--per-group items per group, skewed sizes, random genre sets; a config with
the SVG as its only output), builds it with the release binary, then, each
step a fresh `nptreemap build`:

  random      --edits single-item weight edits, each one item's size times a
              factor from 0.25 to 4 (fills changed, summed over the edits)
  reorder     every item of the middle-ranked group scaled so that it is
              twice the heaviest group: the groups' order by weight changes
  grow        the lightest item of the largest group grown to twice that
              group's heaviest item (which child wears the group's colour)
  revert      the original table back: every fill must be as before

and reports, per step, the fills changed (cells whose fill differs from the
build before the step, and from the first build), once with the colours kept
in the state folder and once with them dropped from the manifest before each
build (warm layout as before, colours chosen afresh: builds before they were
kept), and for the first build
the closest pair of legend colours and of touching groups' colours in
CIEDE2000 (written out below, Sharma, Wu & Dalal 2005). Markdown on stdout.

usage: python3 benches/colors.py [--no-build] [--groups 6,30,120]
       [--per-group 12] [--edits 10] [--seed 1]
Python 3 standard library only.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import platform
import random
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
OUT = TARGET / "colors"
BIN = TARGET / "release" / "nptreemap"

CONFIG = """datasets:
  - name: table
    title: "Generated table, {groups} groups"
    format: genre-table
    files:
      nodes: items.csv
    fields:
      weight: size
      groups: [group]
      genres: tags
    outputs:
      - path: out/table.svg
"""


def linear(c: int) -> float:
    c /= 255
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def cielab(hexcolor: str) -> tuple[float, float, float]:
    r, g, b = (linear(int(hexcolor[k : k + 2], 16)) for k in (1, 3, 5))
    xyz = (
        0.4124564 * r + 0.3575761 * g + 0.1804375 * b,
        0.2126729 * r + 0.7151522 * g + 0.0721750 * b,
        0.0193339 * r + 0.1191920 * g + 0.9503041 * b,
    )
    d = 6 / 29

    def f(t: float) -> float:
        return t ** (1 / 3) if t > d**3 else t / (3 * d * d) + 4 / 29

    fx, fy, fz = (f(v / w) for v, w in zip(xyz, (0.95047, 1.0, 1.08883)))
    return (116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz))


def delta_e(p: str, q: str) -> float:
    """CIEDE2000 of two hex colours (kL = kC = kH = 1)."""
    (l1, a1, b1), (l2, a2, b2) = cielab(p), cielab(q)
    cbar = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2
    g = 0.5 * (1 - math.sqrt(cbar**7 / (cbar**7 + 25**7)))
    a1, a2 = (1 + g) * a1, (1 + g) * a2
    c1, c2 = math.hypot(a1, b1), math.hypot(a2, b2)

    def hue(b: float, a: float) -> float:
        return 0.0 if a == 0 and b == 0 else math.degrees(math.atan2(b, a)) % 360

    h1, h2 = hue(b1, a1), hue(b2, a2)
    dh = 0.0
    if c1 * c2 != 0:
        dh = h2 - h1
        dh = dh if abs(dh) <= 180 else (dh - 360 if dh > 180 else dh + 360)
    big_dh = 2 * math.sqrt(c1 * c2) * math.sin(math.radians(dh / 2))
    lm, cm = (l1 + l2) / 2, (c1 + c2) / 2
    if c1 * c2 == 0:
        hm = h1 + h2
    elif abs(h1 - h2) <= 180:
        hm = (h1 + h2) / 2
    else:
        hm = (h1 + h2 + 360) / 2 if h1 + h2 < 360 else (h1 + h2 - 360) / 2
    t = (
        1
        - 0.17 * math.cos(math.radians(hm - 30))
        + 0.24 * math.cos(math.radians(2 * hm))
        + 0.32 * math.cos(math.radians(3 * hm + 6))
        - 0.20 * math.cos(math.radians(4 * hm - 63))
    )
    theta = 30 * math.exp(-(((hm - 275) / 25) ** 2))
    rc = 2 * math.sqrt(cm**7 / (cm**7 + 25**7))
    sl = 1 + 0.015 * (lm - 50) ** 2 / math.sqrt(20 + (lm - 50) ** 2)
    sc, sh = 1 + 0.045 * cm, 1 + 0.015 * cm * t
    rt = -math.sin(math.radians(2 * theta)) * rc
    x, y, z = (l2 - l1) / sl, (c2 - c1) / sc, big_dh / sh
    return math.sqrt(max(0.0, x * x + y * y + z * z + rt * y * z))


def table(groups: int, per_group: int, rng: random.Random) -> list[list[str]]:
    tags = [f"t{k}" for k in range(4 * groups)]
    rows = []
    for g in range(groups):
        for k in range(per_group):
            size = int(10 ** rng.uniform(1, 4))
            own = rng.sample(tags[4 * g : 4 * g + 4], 2) + rng.sample(tags, 2)
            rows.append([f"g{g}-i{k}", f"g{g}", str(size), "|".join(sorted(set(own)))])
    return rows


def write(path: Path, rows: list[list[str]]) -> None:
    text = "id,group,size,tags\n" + "".join(",".join(r) + "\n" for r in rows)
    path.write_text(text)


def fills(svg: str) -> dict[str, str]:
    out = {}
    for tag in re.findall(r"<path [^>]*>", svg):
        node, fill = re.search(r'data-id="([^"]+)"', tag), re.search(r'fill="(#[0-9a-f]{6})"', tag)
        if node and fill:
            out[node.group(1)] = fill.group(1)
    return out


def legend(svg: str) -> list[str]:
    return re.findall(r'class="np-legend-item">\s*<rect[^>]*fill="(#[0-9a-f]{6})"', svg)


def build(case: Path, forget: bool = False) -> str:
    if forget:
        forget_colours(case)
    run = subprocess.run(
        [str(BIN), "build", str(case / "nptreemap.yaml")], capture_output=True, text=True
    )
    if run.returncode != 0:
        sys.exit(f"build failed in {case}:\n{run.stderr}")
    return (case / "out" / "table.svg").read_text()


def forget_colours(case: Path) -> None:
    """Drops the colours the manifest keeps, and nothing else: the next
    build lays out warm as before and chooses its colours afresh, as builds
    did before the colours were kept."""
    for manifest in (case / "out" / ".nptreemap").glob("*.manifest.json"):
        data = json.loads(manifest.read_text())
        data.pop("colors", None)
        data.pop("shades", None)
        manifest.write_text(json.dumps(data, indent=2) + "\n")


def clear_state(case: Path) -> None:
    state = case / "out" / ".nptreemap"
    if state.exists():
        for f in sorted(state.rglob("*"), reverse=True):
            f.unlink() if f.is_file() else f.rmdir()
        state.rmdir()


def changed(a: dict[str, str], b: dict[str, str]) -> int:
    return sum(1 for k in a if b.get(k) != a[k])


def group_weights(rows: list[list[str]]) -> list[tuple[str, float]]:
    sums: dict[str, float] = {}
    for r in rows:
        sums[r[1]] = sums.get(r[1], 0.0) + float(r[2])
    return sorted(sums.items(), key=lambda kv: (-kv[1], kv[0]))


def closest(colors: list[str]) -> tuple[float, str]:
    best = (math.inf, "")
    for i, a in enumerate(colors):
        for b in colors[:i]:
            d = delta_e(a, b)
            if d < best[0]:
                best = (d, f"{a}/{b}")
    return best


def steps(rows: list[list[str]], edits: int, rng: random.Random) -> list[tuple[str, list[list[str]]]]:
    """The tables built one after another, each with what it changes."""
    out = []
    edited = [r[:] for r in rows]
    for k in range(edits):
        r = rng.randrange(len(edited))
        edited[r][2] = str(max(1, int(float(edited[r][2]) * rng.choice([0.25, 0.5, 2, 4]))))
        out.append((f"random edit {k + 1}", [x[:] for x in edited]))
    order = group_weights(rows)
    middle, heaviest = order[len(order) // 2][0], order[0][1]
    mid_weight = dict(order)[middle]
    reorder = [r[:] for r in rows]
    for r in reorder:
        if r[1] == middle:
            r[2] = str(max(1, int(float(r[2]) * 2 * heaviest / mid_weight)))
    assert group_weights(reorder)[0][0] == middle
    out.append((f"reorder: {middle} (rank {len(order) // 2 + 1} of {len(order)}) made the heaviest", reorder))
    big = order[0][0]
    members = [k for k, r in enumerate(rows) if r[1] == big]
    light = min(members, key=lambda k: float(rows[k][2]))
    grow = [r[:] for r in rows]
    grow[light][2] = str(int(2 * max(float(rows[k][2]) for k in members)))
    out.append((f"grow: {rows[light][0]}, the lightest of {big}, to 2× its heaviest", grow))
    out.append(("revert: the original table", rows))
    return out


def case(groups: int, args: argparse.Namespace) -> list[str]:
    rng = random.Random(args.seed * 1000 + groups)
    dir = OUT / f"g{groups}"
    (dir / "out").mkdir(parents=True, exist_ok=True)
    (dir / "nptreemap.yaml").write_text(CONFIG.format(groups=groups))
    rows = table(groups, args.per_group, rng)
    plan = steps(rows, args.edits, rng)
    counts = {}
    for forget in (False, True):
        clear_state(dir)
        write(dir / "items.csv", rows)
        first = build(dir)
        base = fills(first)
        if not forget:
            swatches = legend(first)
            d, pair = closest(swatches)
        prev = base
        for label, table_rows in plan:
            write(dir / "items.csv", table_rows)
            now = fills(build(dir, forget))
            counts.setdefault(label, []).append((changed(prev, now), changed(base, now)))
            prev = now
    random_label = lambda label: label.startswith("random edit")
    lines = [
        f"**{groups} groups**: {len(base)} cells; the legend's {len(swatches)} swatches "
        f"no closer than ΔE00 {d:.1f} ({pair})",
        "",
        "| step | fills changed, colours kept | of the first build | colours dropped from the state before each build | of the first build |",
        "|---|---:|---:|---:|---:|",
    ]
    randoms = [c for label, c in counts.items() if random_label(label)]
    if randoms:
        kept = sum(c[0][0] for c in randoms)
        afresh = sum(c[1][0] for c in randoms)
        lines.append(
            f"| {len(randoms)} random single-item edits (×0.25–×4), summed | {kept} | "
            f"{randoms[-1][0][1]} | {afresh} | {randoms[-1][1][1]} |"
        )
    for label, c in counts.items():
        if not random_label(label):
            lines.append(f"| {label} | {c[0][0]} | {c[0][1]} | {c[1][0]} | {c[1][1]} |")
    return lines + [""]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-build", action="store_true")
    ap.add_argument("--groups", default="6,30,120")
    ap.add_argument("--per-group", type=int, default=12)
    ap.add_argument("--edits", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if not args.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=REPO, check=True)
    rev = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True
    ).stdout.strip()
    print(f"- date: {dt.datetime.now(dt.timezone.utc):%Y-%m-%d %H:%M} UTC; commit {rev}")
    print(f"- machine: {os.cpu_count()} CPUs, {platform.machine()} {platform.system()}")
    print(f"- command: `python3 benches/colors.py --groups {args.groups} "
          f"--per-group {args.per_group} --edits {args.edits} --seed {args.seed}`")
    print()
    for g in (int(x) for x in args.groups.split(",")):
        print("\n".join(case(g, args)))


if __name__ == "__main__":
    main()
