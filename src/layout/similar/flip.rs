//! Flip moves (paper §9, "Planar Embedding considering Similarity"): an
//! unrealised same-parent constraint `a`–`b` whose sites are one edge flip
//! apart in the Delaunay triangulation of their diagram (the quadrilateral
//! `a c b d` of two triangles) is made a Delaunay edge by moving `a` and `b`
//! towards each other just past the point where `b` enters the circle through
//! `a`, `c` and `d`. The flip only removes the edge `c`–`d`, so `a` and `b`
//! keep every other Delaunay neighbour; a flip whose `c`–`d` is a realised
//! constraint is not proposed. The Delaunay graph is a candidate graph (the
//! cells are weighted): every move is confirmed on the settled power cells.

use super::delaunay::SiteGraph;
use super::level::{Diagram, LevelCtx, Snapshot};
use crate::geom::Point;

/// Diagrams of more children get no flip moves: on a flat diagram of
/// 10,000 cells (`benches/scale.py` flat10000, seed 1) a round of 115 flips
/// lowered the realised constraints from 6,326 to 5,482 and was undone.
const MAX_CHILDREN: usize = 3000;
/// Largest share of the distance `a`–`b` each of the two sites moves.
const MAX_SHARE: f64 = 0.3;
/// Bisection steps finding the least share that flips the quadrilateral.
const SEARCH_STEPS: usize = 12;
/// How far past the least flipping share the sites go (a margin for the
/// weights, which the Delaunay test ignores).
const MARGIN: f64 = 1.25;

/// One proposed move: level-local nodes `a` and `b` and their new sites.
#[derive(Clone, Debug)]
pub(super) struct Flip {
    pub(super) a: usize,
    pub(super) b: usize,
    to: [Point; 2],
    from: [Point; 2],
}

/// The flip moves of one round on the geometry of `snap`: per diagram, the
/// unrealised constraints one flip away, strongest first, no site in two
/// moves' quadrilaterals.
pub(super) fn plan_flips(diagrams: &[Diagram], snap: &Snapshot, lv: &LevelCtx<'_>) -> Vec<Flip> {
    let links = lv.links;
    let mut flips = Vec::new();
    for d in diagrams {
        let Diagram::Sim { children, sim } = d else {
            continue;
        };
        // A move of two sites takes a weight step of the whole diagram, which
        // on a diagram this large moves more neighbourhoods than it makes.
        if children.len() > MAX_CHILDREN {
            continue;
        }
        let pts: Vec<Point> = sim.state().sites.iter().map(|s| s.position).collect();
        let graph = SiteGraph::new(&pts);
        let mut used = vec![false; children.len()];
        // (score, slot a, slot b) of every unrealised same-diagram constraint.
        let mut wanted: Vec<(u8, usize, usize)> = Vec::new();
        for (j, &c) in children.iter().enumerate() {
            let a = links.local[c];
            for &(t, score) in &links.links[a] {
                if t > a && snap.diagram[t] == snap.diagram[a] && !snap.adjacency.are_adjacent(a, t) {
                    wanted.push((score, j, snap.slot[t]));
                }
            }
        }
        wanted.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        for (_, j, k) in wanted {
            if used[j] || used[k] {
                continue;
            }
            let node = |s: usize| links.local[children[s]];
            // The flip removes the edge c-e: not when it is a realised constraint.
            let realised = |c: usize, e: usize| {
                links.score(node(c), node(e)).is_some()
                    && snap.adjacency.are_adjacent(node(c), node(e))
            };
            let quad = graph
                .one_flip(&pts, j, k)
                .into_iter()
                .find(|&(c, e)| !(used[c] || used[e] || realised(c, e)));
            let Some((c, e)) = quad else {
                continue;
            };
            let Some(share) = flipping_share(pts[j], pts[k], pts[c], pts[e]) else {
                continue;
            };
            let step = (pts[k] - pts[j]) * share;
            let to = [pts[j] + step, pts[k] - step];
            if !to.iter().all(|p| sim.clip().contains(*p)) {
                continue;
            }
            for s in [j, k, c, e] {
                used[s] = true;
            }
            flips.push(Flip {
                a: node(j),
                b: node(k),
                to,
                from: [pts[j], pts[k]],
            });
        }
    }
    flips
}

/// Moves the sites of `flips` (`back`: to where they were), one step per
/// diagram touched.
pub(super) fn apply_flips(diagrams: &mut [Diagram], snap: &Snapshot, flips: &[Flip], back: bool) {
    let mut per_diagram: Vec<Vec<(usize, Point)>> = vec![Vec::new(); diagrams.len()];
    for f in flips {
        let at = if back { f.from } else { f.to };
        per_diagram[snap.diagram[f.a]].push((snap.slot[f.a], at[0]));
        per_diagram[snap.diagram[f.b]].push((snap.slot[f.b], at[1]));
    }
    for (d, moves) in diagrams.iter_mut().zip(per_diagram) {
        if moves.is_empty() {
            continue;
        }
        if let Diagram::Sim { sim, .. } = d {
            let mut pos: Vec<Point> = sim.state().sites.iter().map(|s| s.position).collect();
            for (slot, p) in moves {
                pos[slot] = p;
            }
            sim.step_with_positions(&pos);
        }
    }
}

/// The least share of `a`–`b` (each moving that much towards the other)
/// that puts `b` inside the circle through `a`, `c`, `d`, with
/// [`MARGIN`]; `None` beyond [`MAX_SHARE`].
fn flipping_share(a: Point, b: Point, c: Point, d: Point) -> Option<f64> {
    let flipped = |s: f64| {
        let step = (b - a) * s;
        in_circle(a + step, c, d, b - step)
    };
    if !flipped(MAX_SHARE / MARGIN) {
        return None;
    }
    let (mut lo, mut hi) = (0.0, MAX_SHARE / MARGIN);
    for _ in 0..SEARCH_STEPS {
        let mid = 0.5 * (lo + hi);
        if flipped(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi * MARGIN)
}

/// True when `q` lies strictly inside the circle through `p1`, `p2`, `p3`.
fn in_circle(p1: Point, p2: Point, p3: Point, q: Point) -> bool {
    let row = |p: Point| {
        let v = p - q;
        (v.x, v.y, v.length_squared())
    };
    let (ax, ay, aa) = row(p1);
    let (bx, by, bb) = row(p2);
    let (cx, cy, cc) = row(p3);
    let det = ax * (by * cc - bb * cy) - ay * (bx * cc - bb * cx) + aa * (bx * cy - by * cx);
    let orient = (p2 - p1).perp_dot(p3 - p1);
    det * orient.signum() > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_share_found_flips_a_long_rhombus() {
        // Symmetric: it flips once |a'b'| < |cd|, at a share of 0.2 / 4.8.
        let (a, c, b, d) = (
            Point::new(0.0, 0.0),
            Point::new(1.2, -1.0),
            Point::new(2.4, 0.0),
            Point::new(1.2, 1.0),
        );
        assert!(!in_circle(a, c, d, b));
        let s = flipping_share(a, b, c, d).expect("a short move flips it");
        assert!(s > 0.2 / 4.8 && s <= MAX_SHARE);
        let step = (b - a) * s;
        assert!(in_circle(a + step, c, d, b - step));
        // A needle needs more than the largest move.
        let needle = flipping_share(a, Point::new(40.0, 0.0), c, d);
        assert!(needle.is_none());
    }
}
