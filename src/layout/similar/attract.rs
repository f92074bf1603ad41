//! Attraction moves (paper Algorithm 2, method-reference §5.4–5.7): each cell
//! steps its site towards its furthest strongest unrealised partner, slides
//! along the parent edge towards a cousin, or stays; then every site is pulled
//! a little towards its cell's centroid. A move is judged by what it does to
//! the cell's shape as well as to its neighbourhoods: one that takes a site too
//! far off its centroid (a long cell) is not made.

use super::level::Snapshot;
use super::links::LevelLinks;
use super::params::Distances;
use crate::geom::{step_towards, ConvexPolygon, Point};
use crate::layout::map::MapSimulation;

/// New site positions for one diagram: Algorithm 2 for each cell, furthest
/// strongest link first (§5.4), at most one successful move per cell (§5.6).
pub(super) fn attraction_moves(
    children: &[usize],
    sim: &MapSimulation,
    links: &LevelLinks,
    snap: &Snapshot,
    limits: &Distances,
    attract: bool,
) -> Vec<Point> {
    let state = sim.state();
    let clip = sim.clip();
    let targets = sim.targets();
    let mut pos: Vec<Point> = state.sites.iter().map(|s| s.position).collect();
    let local: Vec<usize> = children.iter().map(|c| links.local[*c]).collect();
    let gap = limits.gap;
    let mover = Mover {
        clip,
        links,
        snap,
        limits,
    };
    // Order: decreasing distance to the strongest partner, ties by index.
    let mut order: Vec<(f64, usize)> = (0..children.len())
        .map(|j| {
            let d = links.links[local[j]]
                .first()
                .map(|(t, _)| pos[j].distance(snap.site[*t]))
                .unwrap_or(0.0);
            (d, j)
        })
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for (_, j) in order {
        let me = local[j];
        let cell = &state.diagram.cells[j];
        let centroid = cell.centroid;
        let offset_limit = limits.max_offset * targets[j].max(0.0).sqrt();
        let neighbors_here: Vec<usize> = cell.neighbors.iter().map(|nb| nb.site).collect();
        let accept = |p: Point, pos: &[Point], cross_parent: bool| -> bool {
            clip.contains(p)
                && neighbors_here.iter().all(|&o| p.distance(pos[o]) >= gap)
                && (!cross_parent || clip.boundary_distance(p) >= gap)
                && (limits.max_offset.is_infinite()
                    || p.distance(centroid) <= offset_limit
                    || p.distance(centroid) <= pos[j].distance(centroid))
        };
        let moved = attract
            && !links.links[me].is_empty()
            && cell.polygon.is_some()
            && mover.attract(j, me, centroid, &mut pos, accept);
        if cell.polygon.is_none() {
            continue;
        }
        let share = if moved {
            limits.pull
        } else {
            limits.idle_step.max(limits.pull)
        };
        if share > 0.0 {
            let p = pos[j] + (centroid - pos[j]) * share;
            if clip.contains(p) {
                pos[j] = p;
            }
        }
    }
    pos
}

/// What one diagram's attraction moves read, the same for every cell.
struct Mover<'a> {
    clip: &'a ConvexPolygon,
    links: &'a LevelLinks,
    snap: &'a Snapshot,
    limits: &'a Distances,
}

impl Mover<'_> {
    /// Tries cell `j`'s (level-local `me`) links: different parent first,
    /// then same parent, each by distance, furthest first (§5.5); makes the
    /// first move `accept` takes and says whether one was made. A slide that
    /// only aligns along the parent edge is not a move of its own (§5.6 rule
    /// 8): it is made and the search goes on.
    fn attract(
        &self,
        j: usize,
        me: usize,
        centroid: Point,
        pos: &mut [Point],
        accept: impl Fn(Point, &[Point], bool) -> bool,
    ) -> bool {
        let (links, snap, clip, limits) = (self.links, self.snap, self.clip, self.limits);
        let (step, d_opt) = (limits.step, limits.d_opt);
        let mut records: Vec<(bool, f64, usize, u8)> = links.links[me]
            .iter()
            .map(|&(t, s)| {
                let same = snap.diagram[t] == snap.diagram[me];
                let target = if same {
                    pos[snap.slot[t]]
                } else {
                    snap.site[t]
                };
                (same, pos[j].distance(target), t, s)
            })
            .collect();
        records.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        for (same, dist, t, score) in records {
            let neighbor = snap.adjacency.are_adjacent(me, t);
            if same {
                if neighbor || dist < d_opt || !has_free_neighbor(links, snap, t, score) {
                    continue;
                }
                let target = pos[snap.slot[t]];
                if let Some(p) = step_towards(pos[j], target, step) {
                    if accept(p, pos, false) {
                        pos[j] = p;
                        return true;
                    }
                }
                continue;
            }
            let (d, edge) = clip.exit_through(centroid, snap.centroid[t]);
            let toward = step_towards(pos[j], snap.site[t], step);
            let slide =
                edge.and_then(|(a, b)| slide_along(pos[j], centroid, snap.centroid[t], a, b, step));
            let candidate = if neighbor {
                if d <= limits.d_max {
                    slide
                } else {
                    toward
                }
            } else if d > d_opt {
                toward
            } else {
                if let Some(p) = slide {
                    if accept(p, pos, true) {
                        pos[j] = p;
                    }
                }
                continue;
            };
            if let Some(p) = candidate {
                if accept(p, pos, true) {
                    pos[j] = p;
                    return true;
                }
            }
        }
        false
    }
}

/// Does target `t` have a neighbour that a link of strength `score` could
/// displace: one without a constraint to `t`, or with a weaker one (the
/// paper's Fig. 4e/f test)?
fn has_free_neighbor(links: &LevelLinks, snap: &Snapshot, t: usize, score: u8) -> bool {
    snap.adjacency
        .neighbors(t)
        .iter()
        .any(|&m| links.score(t, m).is_none_or(|s| s < score))
}

/// The slide along a parent edge `a`–`b` that aligns the projections of the
/// two centroids on it (§5.7b), or `None` when already aligned.
fn slide_along(
    p: Point,
    source: Point,
    target: Point,
    a: Point,
    b: Point,
    step: f64,
) -> Option<Point> {
    let u = (b - a).normalize_or_zero();
    let gap = (target - a).dot(u) - (source - a).dot(u);
    (gap.abs() > step).then(|| p + u * (step * gap.signum()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slide_aligns_projections_and_stops_when_aligned() {
        let (a, b) = (Point::new(10.0, 0.0), Point::new(10.0, 10.0));
        let p = Point::new(8.0, 2.0);
        let moved = slide_along(p, p, Point::new(12.0, 8.0), a, b, 0.5).expect("not aligned");
        assert_eq!(moved, Point::new(8.0, 2.5));
        assert!(slide_along(p, p, Point::new(12.0, 2.2), a, b, 0.5).is_none());
    }
}
