#!/usr/bin/env python3
"""nptreemap's own independent checker for a layout JSON file (`nptreemap-layout/1`).

What this file owns: re-checking a layout from its polygons alone, for the tests
(tests/suite/support.rs runs it on every layout a test writes). It shares no code
with the Rust crate and uses only the Python 3 standard library. It follows the
format's spec (layout-json.md: node fields, constraints, the rules below) and
reports the same figures, under the same names, as the project's shared checker
(shared/tools/check-layout), so the two can be compared
(tests/tools/compare_checkers.py).

Usage: check_layout.py LAYOUT.json [--min-shared FRACTION] [--quiet]

Prints one JSON object. Exit status 0 when the layout is sound, 1 when a rule
breaks (the report's `problems` say which), 2 when the file cannot be read.

Rules (each broken one is a line in `problems`):
  - `format` is "nptreemap-layout/1"; node ids are unique; there is one root;
    every `parent` names an existing node; `depth` is 0 at the root and the
    parent's depth + 1 below it;
  - every polygon has at least 3 finite points, a non-zero area, and is convex
    (turns all one way, and winds around exactly once);
  - every child's vertices lie inside its parent's polygon (within 1e-5 of the
    extent diagonal);
  - the children's areas add up to their parent's within 1e-4 of it, and
    siblings do not overlap by more than 1e-4 of the parent's area;
  - every constraint joins two nodes with polygons on the same depth, and its
    `realized` flag agrees with the geometry.

Geometry of "realised": two cells share an edge when the length of boundary they
have in common is at least FRACTION (default 1e-6) of the extent diagonal. The
extent is the bounding box of all polygons, i.e. of the root's cell, which spans
the canvas in nptreemap's outlines (rect, circle, ngon), so this is the spec's
canvas diagonal; the shared checker measures it the same way. Common boundary is measured along the edges of
the cell that comes first in the file: an edge of the other cell counts where
both its ends lie within 1e-5 of the diagonal of that edge's line, for the part
whose projection falls on the edge.

Figures reported:
  nodes, leaves, levels (deepest declared depth + 1);
  constraints_lowest / realized_lowest / realized_lowest_pct at the deepest
  level, constraints_by_depth {depth: {constraints, realized}};
  area_error_share_mean / _max: |cell area / parent area - weight / sibling
  weight sum| over nodes below the root (a node's `drawn_weight` when it has
  one, as nptreemap writes for items of weight 0 drawn at a floor; with
  --min-weight-ratio R, each weight first raised to R times its heaviest
  sibling's, as the layout does);
  area_error_diagram_mean / _max: per parent, the sum of those errors over its
  children (d3-voronoi-map's convergence ratio), mean and max over parents;
  aspect_ratio_mean: mean bounding-box aspect ratio (long / short side) of leaves;
  graph_distance_median / _max: hops between the two leaves of each deepest-level
  constraint on the leaf adjacency graph (pairs in different components skipped;
  graph_distance_unreachable counts them);
  worst_partition_error: max over parents of |children's area sum - parent
  area| / parent area; worst_sibling_overlap: max over parents of the siblings'
  pairwise overlap area / parent area; worst_containment_excess: the farthest a
  child's vertex lies outside its parent, / extent diagonal;
  checks: how many polygons failed each geometric rule;
  problems (the first 50), problem_count; warnings (never fail the check).
The mean/max figures are rounded as the shared checker rounds them (5 decimals,
aspect 4, percentage 2); --quiet prints only ok, the two lowest-level counts,
area_error_share_mean and problem_count.
"""

import argparse
import json
import math
import sys
from collections import deque

FORMAT = "nptreemap-layout/1"
CONTAINMENT_TOL = 1e-5  # of the extent diagonal
COLLINEAR_TOL = 1e-5  # of the extent diagonal: an edge lies on another's line
PARTITION_TOL = 1e-4  # of the parent's area
OVERLAP_TOL = 1e-4  # of the parent's area
TURN_TOL = 1e-9  # |sin| of a turn below which a vertex counts as straight
MAX_PROBLEMS = 50


class BadInput(Exception):
    """The file is not a layout at all (exit status 2)."""


# ---------------------------------------------------------------- geometry


def shoelace(poly):
    """Signed area: positive for counter-clockwise in a y-up frame."""
    total = 0.0
    prev = poly[-1]
    for cur in poly:
        total += prev[0] * cur[1] - cur[0] * prev[1]
        prev = cur
    return 0.5 * total


def bounds(poly):
    xs = [p[0] for p in poly]
    ys = [p[1] for p in poly]
    return (min(xs), min(ys), max(xs), max(ys))


def boxes_meet(a, b, pad):
    return not (a[0] > b[2] + pad or b[0] > a[2] + pad or a[1] > b[3] + pad or b[1] > a[3] + pad)


def edges(poly):
    """(start, end) of every edge, closing the ring."""
    n = len(poly)
    return [(poly[i], poly[(i + 1) % n]) for i in range(n)]


def convex(poly, merge_dist):
    """True when the ring turns one way only and winds around exactly once.

    Vertices closer than merge_dist to the previous kept one are dropped first,
    so that rounding noise on a near-zero edge does not fake a turn.
    """
    ring = []
    for p in poly:
        if not ring or math.dist(p, ring[-1]) > merge_dist:
            ring.append(p)
    while len(ring) > 1 and math.dist(ring[0], ring[-1]) <= merge_dist:
        ring.pop()
    if len(ring) < 3:
        return False
    direction = 0
    winding = 0.0
    n = len(ring)
    for i in range(n):
        o, p, q = ring[i - 1], ring[i], ring[(i + 1) % n]
        ux, uy = p[0] - o[0], p[1] - o[1]
        vx, vy = q[0] - p[0], q[1] - p[1]
        cross = ux * vy - uy * vx
        dot = ux * vx + uy * vy
        winding += math.atan2(cross, dot)
        size = math.hypot(ux, uy) * math.hypot(vx, vy)
        if size == 0.0 or abs(cross) <= TURN_TOL * size:
            continue
        turn = 1 if cross > 0 else -1
        if direction == 0:
            direction = turn
        elif turn != direction:
            return False
    return abs(abs(winding) - 2.0 * math.pi) < 1e-6


def inward_distances(pt, poly):
    """Smallest signed distance from pt to the lines of poly's edges, positive inside."""
    orient = 1.0 if shoelace(poly) >= 0.0 else -1.0
    worst = math.inf
    for (ax, ay), (bx, by) in edges(poly):
        ex, ey = bx - ax, by - ay
        length = math.hypot(ex, ey)
        if length == 0.0:
            continue
        d = orient * (ex * (pt[1] - ay) - ey * (pt[0] - ax)) / length
        worst = min(worst, d)
    return worst


def clip_convex(subject, clip):
    """Sutherland-Hodgman: the part of `subject` inside the convex `clip`."""
    if shoelace(clip) < 0.0:
        clip = clip[::-1]
    out = list(subject)
    for (ax, ay), (bx, by) in edges(clip):
        if not out:
            break
        src, out = out, []

        def side(p):
            return (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax)

        prev = src[-1]
        s_prev = side(prev)
        for cur in src:
            s_cur = side(cur)
            if s_cur >= 0.0:
                if s_prev < 0.0:
                    out.append(cut(prev, cur, s_prev, s_cur))
                out.append(cur)
            elif s_prev >= 0.0:
                out.append(cut(prev, cur, s_prev, s_cur))
            prev, s_prev = cur, s_cur
    return out


def cut(p, q, sp, sq):
    t = sp / (sp - sq)
    return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))


def overlap_area(a, b):
    part = clip_convex(a, b)
    return abs(shoelace(part)) if len(part) >= 3 else 0.0


def common_boundary(first, second, near):
    """Length of `first`'s boundary that `second`'s boundary runs along (see the docs)."""
    total = 0.0
    other = edges(second)
    for p, q in edges(first):
        length = math.dist(p, q)
        if length == 0.0:
            continue
        ux, uy = (q[0] - p[0]) / length, (q[1] - p[1]) / length
        for r, s in other:
            off_r = abs(ux * (r[1] - p[1]) - uy * (r[0] - p[0]))
            if off_r > near:
                continue
            off_s = abs(ux * (s[1] - p[1]) - uy * (s[0] - p[0]))
            if off_s > near:
                continue
            tr = ux * (r[0] - p[0]) + uy * (r[1] - p[1])
            ts = ux * (s[0] - p[0]) + uy * (s[1] - p[1])
            lo = max(0.0, min(tr, ts))
            hi = min(length, max(tr, ts))
            if hi > lo:
                total += hi - lo
    return total


# ---------------------------------------------------------------- the check


class Report:
    def __init__(self):
        self.problems = []
        self.warnings = []

    def problem(self, text):
        self.problems.append(text)

    def warn(self, text):
        self.warnings.append(text)


def finite_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def read_polygon(raw):
    """The polygon as a list of (x, y) floats, or None when it is not a valid one."""
    if not isinstance(raw, list) or len(raw) < 3:
        return None
    pts = []
    for pt in raw:
        if not (isinstance(pt, list) and len(pt) == 2 and all(finite_number(c) for c in pt)):
            return None
        pts.append((float(pt[0]), float(pt[1])))
    return pts


def weight_of(node):
    # The weight the node is drawn at: `drawn_weight` when the producer says
    # it drew the node at another size than its weight (nptreemap's
    # `zero_weights: floor` gives an item of weight 0 the floor), else `weight`.
    w = node.get("drawn_weight", node.get("weight"))
    return float(w) if finite_number(w) else 0.0


def median(values):
    if not values:
        return None
    s = sorted(values)
    mid = len(s) // 2
    return s[mid] if len(s) % 2 else (s[mid - 1] + s[mid]) / 2


def rounded(value, digits):
    return None if value is None else round(value, digits)


def mean(values):
    return sum(values) / len(values) if values else None


def check(doc, min_shared, min_weight_ratio=0.0):
    rep = Report()
    if not isinstance(doc, dict) or not isinstance(doc.get("nodes"), list):
        raise BadInput("no `nodes` list")
    nodes = doc["nodes"]
    constraints = doc.get("constraints", [])
    if not isinstance(constraints, list):
        raise BadInput("`constraints` is not a list")
    if any(not isinstance(n, dict) for n in nodes) or any(not isinstance(c, dict) for c in constraints):
        raise BadInput("a node or constraint is not an object")

    if doc.get("format") != FORMAT:
        rep.problem(f"format is {doc.get('format')!r}, not {FORMAT!r}")

    # --- the tree
    node_of = {}  # id -> node (the last one when ids repeat)
    order = {}  # id -> index of its first appearance
    for i, n in enumerate(nodes):
        nid = n.get("id")
        if nid in node_of:
            rep.problem(f"node id {nid!r} appears twice")
        else:
            order[nid] = i
        node_of[nid] = n
    kids = {}  # parent id -> child ids in file order (parents in order of first child)
    roots = []
    for n in nodes:
        parent = n.get("parent")
        if parent is None:
            roots.append(n.get("id"))
        elif parent in node_of:
            kids.setdefault(parent, []).append(n.get("id"))
        else:
            rep.problem(f"node {n.get('id')!r}: parent {parent!r} does not exist")
    if len(roots) != 1:
        rep.problem(f"{len(roots)} roots (nodes without a parent), expected one")
    depth_of = {n.get("id"): n.get("depth") for n in nodes}
    for n in nodes:
        d, parent = n.get("depth"), n.get("parent")
        if not isinstance(d, int) or isinstance(d, bool):
            rep.problem(f"node {n.get('id')!r}: depth {d!r} is not an integer")
        elif parent is None and d != 0:
            rep.problem(f"root {n.get('id')!r} has depth {d}, not 0")
        elif parent in node_of and isinstance(depth_of[parent], int) and d != depth_of[parent] + 1:
            rep.problem(f"node {n.get('id')!r} has depth {d}, its parent {depth_of[parent]}")

    # --- polygons
    poly_of = {}
    for n in nodes:
        poly = read_polygon(n.get("polygon"))
        if poly is None:
            rep.problem(f"node {n.get('id')!r}: polygon missing, shorter than 3 points or not finite")
        else:
            poly_of[n.get("id")] = poly
    points = [p for poly in poly_of.values() for p in poly]
    if points:
        x0, y0, x1, y1 = bounds(points)
        diag = math.hypot(x1 - x0, y1 - y0) or 1.0
    else:
        diag = 1.0
    area_of = {nid: abs(shoelace(poly)) for nid, poly in poly_of.items()}

    checks = {"polygon_missing": len(nodes) - len(poly_of), "zero_area": 0, "not_convex": 0,
              "outside_parent": 0, "partition": 0, "overlap": 0}
    for nid, poly in poly_of.items():
        if area_of[nid] <= 0.0:
            checks["zero_area"] += 1
            rep.problem(f"node {nid!r}: polygon has zero area")
        if not convex(poly, 1e-9 * diag):
            checks["not_convex"] += 1
            rep.problem(f"node {nid!r}: polygon is not convex")

    canvas = doc.get("canvas")
    if isinstance(canvas, dict) and finite_number(canvas.get("width")) and finite_number(canvas.get("height")) \
            and canvas["width"] > 0 and canvas["height"] > 0:
        if roots and roots[0] in poly_of:
            bx0, by0, bx1, by1 = bounds(poly_of[roots[0]])
            slack = CONTAINMENT_TOL * diag
            if bx0 < -slack or by0 < -slack or bx1 > canvas["width"] + slack or by1 > canvas["height"] + slack:
                rep.warn("the root's polygon reaches outside the canvas")
    else:
        rep.warn("no valid canvas {width, height}")

    # --- containment, partition, overlap
    worst_partition = 0.0
    worst_overlap = 0.0
    worst_excess = 0.0
    for parent, children in kids.items():
        outer = poly_of.get(parent)
        if outer is None:
            continue
        parent_area = area_of[parent]
        inside = [c for c in children if c in poly_of]
        for c in inside:
            lowest = min(inward_distances(p, outer) for p in poly_of[c])
            if lowest < 0.0:
                worst_excess = max(worst_excess, -lowest / diag)
            if lowest < -CONTAINMENT_TOL * diag:
                checks["outside_parent"] += 1
                rep.problem(f"node {c!r} reaches {-lowest:.6g} outside its parent {parent!r}")
        if parent_area > 0.0 and children:
            covered = sum(area_of[c] for c in inside)
            rel = abs(covered - parent_area) / parent_area
            worst_partition = max(worst_partition, rel)
            if rel > PARTITION_TOL:
                checks["partition"] += 1
                rep.problem(f"children of {parent!r} cover {covered / parent_area:.6f} of its area")
            overlap = sibling_overlap(inside, poly_of, CONTAINMENT_TOL * diag) / parent_area
            worst_overlap = max(worst_overlap, overlap)
            if overlap > OVERLAP_TOL:
                checks["overlap"] += 1
                rep.problem(f"children of {parent!r} overlap on {overlap:.6f} of its area")

    # --- area error and aspect ratio
    share_errors, diagram_errors = [], []
    for parent, children in kids.items():
        inside = [c for c in children if c in poly_of]
        if parent not in poly_of or not inside:
            continue
        # The layout floors a child lighter than min_weight_ratio of its
        # heaviest sibling to that share (README, "Zero weights"); 0 (the
        # default here) judges the areas against the raw weights.
        heaviest = max(weight_of(node_of[c]) for c in inside)
        target = {c: max(weight_of(node_of[c]), heaviest * min_weight_ratio) for c in inside}
        total_weight = sum(target.values())
        parent_area = area_of[parent]
        if total_weight <= 0.0 or parent_area <= 0.0:
            continue
        errs = [abs(area_of[c] / parent_area - target[c] / total_weight) for c in inside]
        share_errors.extend(errs)
        diagram_errors.append(sum(errs))
    leaves = [n.get("id") for n in nodes if n.get("id") not in kids and n.get("id") in poly_of]
    aspects = []
    for leaf in leaves:
        bx0, by0, bx1, by1 = bounds(poly_of[leaf])
        short, long_ = sorted((bx1 - bx0, by1 - by0))
        if short > 0.0:
            aspects.append(long_ / short)

    # --- constraints
    deepest = max((d for d in depth_of.values() if isinstance(d, int) and not isinstance(d, bool)), default=0)
    near = COLLINEAR_TOL * diag
    threshold = min_shared * diag
    box_of = {nid: bounds(poly) for nid, poly in poly_of.items()}

    def touching(a, b):
        if order[a] > order[b]:
            a, b = b, a
        if not boxes_meet(box_of[a], box_of[b], 2.0 * near):
            return False
        return common_boundary(poly_of[a], poly_of[b], near) >= threshold

    per_depth = {}
    seen_pairs = set()
    dangling = wrong_flags = 0
    lowest_pairs = []
    for c in constraints:
        a, b = c.get("a"), c.get("b")
        if a not in poly_of or b not in poly_of:
            dangling += 1
            continue
        if depth_of[a] != depth_of[b]:
            rep.problem(f"constraint {a!r}-{b!r} joins depth {depth_of[a]} to depth {depth_of[b]}")
            continue
        if a == b:
            rep.problem(f"constraint {a!r}-{b!r} joins a node to itself")
        pair = frozenset((a, b))
        if pair in seen_pairs:
            rep.problem(f"constraint {a!r}-{b!r} is listed twice")
        seen_pairs.add(pair)
        real = a != b and touching(a, b)
        counts = per_depth.setdefault(depth_of[a], {"constraints": 0, "realized": 0})
        counts["constraints"] += 1
        counts["realized"] += int(real)
        if "realized" in c and bool(c["realized"]) != real:
            wrong_flags += 1
        if depth_of[a] == deepest:
            lowest_pairs.append((a, b))
        sim, strength = c.get("similarity"), c.get("strength")
        if sim is not None and not (finite_number(sim) and 0.0 <= sim <= 1.0):
            rep.warn(f"constraint {a!r}-{b!r}: similarity {sim!r} is not in [0, 1]")
        if strength is not None and strength not in (1, 2, 3):
            rep.warn(f"constraint {a!r}-{b!r}: strength {strength!r} is not 1, 2 or 3")
    if dangling:
        rep.problem(f"{dangling} constraints name nodes that do not exist or have no polygon")
    if wrong_flags:
        rep.problem(f"{wrong_flags} constraints carry a `realized` flag the geometry contradicts")

    # --- hops between constrained leaves on the deepest level's adjacency graph
    hops, unreachable = [], 0
    if lowest_pairs:
        level = sorted((nid for nid in poly_of if depth_of[nid] == deepest), key=lambda n: order[n])
        graph = adjacency(level, box_of, 2.0 * near, touching)
        for a, b in lowest_pairs:
            dist = hop_count(graph, a, b)
            if dist is None:
                unreachable += 1
            else:
                hops.append(dist)

    lowest = per_depth.get(deepest, {"constraints": 0, "realized": 0})
    return {
        "ok": not rep.problems,
        "nodes": len(nodes),
        "leaves": len(leaves),
        "levels": deepest + 1,
        "constraints_lowest": lowest["constraints"],
        "realized_lowest": lowest["realized"],
        "realized_lowest_pct": round(100.0 * lowest["realized"] / lowest["constraints"], 2)
        if lowest["constraints"] else None,
        "constraints_by_depth": {str(d): per_depth[d] for d in sorted(per_depth)},
        "area_error_share_mean": rounded(mean(share_errors), 5),
        "area_error_share_max": rounded(max(share_errors, default=None), 5),
        "area_error_diagram_mean": rounded(mean(diagram_errors), 5),
        "area_error_diagram_max": rounded(max(diagram_errors, default=None), 5),
        "aspect_ratio_mean": rounded(mean(aspects), 4),
        "graph_distance_median": median(hops),
        "graph_distance_max": max(hops, default=None),
        "graph_distance_unreachable": unreachable,
        "worst_partition_error": worst_partition,
        "worst_sibling_overlap": worst_overlap,
        "worst_containment_excess": worst_excess,
        "extent_diagonal": diag,
        "min_shared_length": threshold,
        "checks": checks,
        "problems": rep.problems[:MAX_PROBLEMS],
        "problem_count": len(rep.problems),
        "warnings": rep.warnings[:MAX_PROBLEMS],
        "checker": "nptreemap tests/tools/check_layout.py",
    }


def sweep_pairs(ids, box_of, pad):
    """Pairs (a, b) of ids whose bounding boxes meet within pad, a before b in `ids`."""
    rank = {nid: i for i, nid in enumerate(ids)}
    by_left = sorted(ids, key=lambda n: box_of[n][0])
    active = []
    for nid in by_left:
        left = box_of[nid][0]
        active = [o for o in active if box_of[o][2] + pad >= left]
        for other in active:
            if boxes_meet(box_of[nid], box_of[other], pad):
                yield (other, nid) if rank[other] < rank[nid] else (nid, other)
        active.append(nid)


def sibling_overlap(ids, poly_of, pad):
    box_of = {nid: bounds(poly_of[nid]) for nid in ids}
    return sum(overlap_area(poly_of[a], poly_of[b]) for a, b in sweep_pairs(ids, box_of, pad))


def adjacency(ids, box_of, pad, touching):
    graph = {nid: set() for nid in ids}
    for a, b in sweep_pairs(ids, box_of, pad):
        if touching(a, b):
            graph[a].add(b)
            graph[b].add(a)
    return graph


def hop_count(graph, a, b):
    """Edges on a shortest path from a to b, or None when b cannot be reached."""
    if a == b:
        return 0
    dist = {a: 0}
    queue = deque([a])
    while queue:
        u = queue.popleft()
        for v in graph.get(u, ()):
            if v not in dist:
                dist[v] = dist[u] + 1
                if v == b:
                    return dist[v]
                queue.append(v)
    return None


QUIET_FIELDS = ("ok", "realized_lowest", "constraints_lowest", "area_error_share_mean", "problem_count")


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="check_layout.py",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("layout", help="the layout JSON file to check")
    parser.add_argument("--min-shared", type=float, default=1e-6, metavar="FRACTION",
                        help="shortest common boundary that counts as a shared edge, "
                             "as a fraction of the extent diagonal (default 1e-6)")
    parser.add_argument("--min-weight-ratio", type=float, default=0.0, metavar="R",
                        help="judge areas against weights floored to R times the heaviest "
                             "sibling's, as the layout's min_weight_ratio does (default 0: "
                             "the raw weights, as the shared checker does)")
    parser.add_argument("--quiet", action="store_true", help="print only the headline figures")
    args = parser.parse_args(argv)
    try:
        with open(args.layout, encoding="utf-8") as f:
            doc = json.load(f)
        report = check(doc, args.min_shared, args.min_weight_ratio)
    except (OSError, ValueError, BadInput) as e:
        print(json.dumps({"ok": False, "error": f"cannot read layout: {e}"}))
        return 2
    if args.quiet:
        report = {k: report[k] for k in QUIET_FIELDS}
    print(json.dumps(report, indent=None if args.quiet else 1))
    return 0 if report["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
