//! Swaps of same-parent cells (method-reference §4.4): greedy rounds whose gains
//! are read off the current adjacency (exchanging two sites with their weights
//! exchanges their cells, so the gain is exact for the geometry at hand), and
//! on small levels an exhaustive polish that measures each swap after settling
//! the areas, judged locally: only the one diagram is settled and only the pairs
//! touching its cells are counted, never the whole level.

use rayon::prelude::*;

use super::level::{aspect, settle, Diagram, LevelCtx};
use crate::geom::shared_edge::PERPENDICULAR_TOL;
use crate::geom::{level_adjacency, Point};

/// Levels up to this many cells get the exhaustive swap polish.
pub(super) const EXHAUSTIVE_MAX_CELLS: usize = 64;
/// Most swap evaluations of the exhaustive polish per level and start.
const EXHAUSTIVE_BUDGET: usize = 400;

/// One greedy swap round over the level (method-reference §4.4): candidate
/// pairs of same-parent cells whose exchange realises more constraints, best
/// gain first, each cell swapped at most once and its neighbours left alone.
/// Returns the number of swaps made.
pub(super) fn swap_round(diagrams: &mut [Diagram], lv: &LevelCtx<'_>) -> usize {
    swap_round_within(diagrams, lv, f64::INFINITY)
}

/// [`swap_round`] among pairs of cells whose target areas are within
/// `max_ratio` of each other: exchanging two sites with their weights
/// exchanges their cells, and cells of similar targets settle back to their
/// own areas in a few weight steps with the sites held in place.
pub(super) fn swap_round_within(
    diagrams: &mut [Diagram],
    lv: &LevelCtx<'_>,
    max_ratio: f64,
) -> usize {
    let links = lv.links;
    let snap = lv.snapshot(diagrams);
    let adj = &snap.adjacency;
    // What node x's partners (own and lifted) adjacent to the cell at `at` are worth.
    let realized = |x: usize, at: usize| -> i64 {
        links.worth(x, |t| t != at && adj.are_adjacent(t, at)) as i64
    };
    let mut candidates: Vec<(i64, usize, usize)> = Vec::new();
    for a in 0..links.nodes.len() {
        if matches!(diagrams[snap.diagram[a]], Diagram::Single { .. }) {
            continue;
        }
        // Only cells next to a partner of `a` can gain by taking a's node.
        let mut seen: Vec<usize> = Vec::new();
        let partners = links.links[a].iter().map(|(t, _)| *t);
        for t in partners.chain(links.lifted[a].iter().map(|(t, _)| *t)) {
            for &b in adj.neighbors(t) {
                if b != a && snap.diagram[b] == snap.diagram[a] && !seen.contains(&b) {
                    seen.push(b);
                }
            }
        }
        for b in seen {
            let now = realized(a, a) + realized(b, b);
            let after = realized(a, b) + realized(b, a);
            let gain = after - now;
            if gain > 0 && target_ratio(&diagrams[snap.diagram[a]], snap.slot[a], snap.slot[b]) <= max_ratio {
                let (x, y) = if a < b { (a, b) } else { (b, a) };
                candidates.push((gain, x, y));
            }
        }
    }
    candidates.sort_by(|p, q| q.0.cmp(&p.0).then(p.1.cmp(&q.1)).then(p.2.cmp(&q.2)));
    candidates.dedup();
    let mut dirty = vec![false; links.nodes.len()];
    let mut per_diagram: Vec<Vec<(usize, usize)>> = vec![Vec::new(); diagrams.len()];
    let mut applied = 0;
    for (_, a, b) in candidates {
        if dirty[a] || dirty[b] {
            continue;
        }
        for x in [a, b] {
            dirty[x] = true;
            for &y in adj.neighbors(x) {
                dirty[y] = true;
            }
        }
        per_diagram[snap.diagram[a]].push((snap.slot[a], snap.slot[b]));
        applied += 1;
    }
    diagrams
        .par_iter_mut()
        .zip(per_diagram.par_iter())
        .for_each(|(d, pairs)| {
            if let Diagram::Sim { sim, .. } = d {
                sim.swap_sites(pairs);
            }
        });
    applied
}

/// The ratio of the larger to the smaller target area of slots `a` and `b`.
fn target_ratio(d: &Diagram, a: usize, b: usize) -> f64 {
    match d {
        Diagram::Sim { sim, .. } => {
            let t = sim.targets();
            t[a].max(t[b]) / t[a].min(t[b]).max(f64::MIN_POSITIVE)
        }
        Diagram::Single { .. } => 1.0,
    }
}

/// On small levels, try every same-parent swap, each measured on the settled
/// geometry, keeping each that raises the level's score (first improvement),
/// within an evaluation budget. The greedy rounds estimate gains from the old
/// adjacency; this measures them, locally (see [`local_value`]).
pub(super) fn exhaustive_polish(diagrams: &mut [Diagram], lv: &LevelCtx<'_>) {
    if lv.links.nodes.len() > EXHAUSTIVE_MAX_CELLS {
        return;
    }
    let mut evaluations = 0;
    let mut improved = true;
    while improved && evaluations < EXHAUSTIVE_BUDGET {
        improved = false;
        'search: for d in 0..diagrams.len() {
            let k = match &diagrams[d] {
                Diagram::Sim { children, .. } => children.len(),
                Diagram::Single { .. } => continue,
            };
            let base = local_value(diagrams, d, None, lv);
            for a in 0..k {
                for b in a + 1..k {
                    let mut trial = diagrams[d].clone();
                    if let Diagram::Sim { sim, .. } = &mut trial {
                        sim.swap_sites(&[(a, b)]);
                    }
                    settle(&mut trial, lv.np);
                    evaluations += 1;
                    if local_value(diagrams, d, Some(&trial), lv) > base {
                        diagrams[d] = trial;
                        improved = true;
                        break 'search;
                    }
                    if evaluations >= EXHAUSTIVE_BUDGET {
                        break 'search;
                    }
                }
            }
        }
    }
}

/// The part of the level's score that diagram `d` (or `replacement` in its
/// place) can change: constraints with an end in one of its cells, against the
/// shape of its cells. Only cells of diagrams whose parent's box meets `d`'s go
/// into the adjacency.
fn local_value(
    diagrams: &[Diagram],
    d: usize,
    replacement: Option<&Diagram>,
    lv: &LevelCtx<'_>,
) -> f64 {
    let links = lv.links;
    let at = |e: usize| -> &Diagram {
        match replacement {
            Some(r) if e == d => r,
            _ => &diagrams[e],
        }
    };
    let pad = Point::splat(2.0 * PERPENDICULAR_TOL * lv.scale);
    let (lo, hi) = at(d).clip().bbox();
    let (lo, hi) = (lo - pad, hi + pad);
    // (level-local index, diagram, slot) of every cell that might count.
    let mut cells: Vec<(usize, usize, usize)> = Vec::new();
    for e in 0..diagrams.len() {
        let (elo, ehi) = at(e).clip().bbox();
        if elo.x > hi.x || elo.y > hi.y || ehi.x < lo.x || ehi.y < lo.y {
            continue;
        }
        match at(e) {
            Diagram::Single { child, .. } => cells.push((links.local[*child], e, 0)),
            Diagram::Sim { children, .. } => {
                for (j, c) in children.iter().enumerate() {
                    cells.push((links.local[*c], e, j));
                }
            }
        }
    }
    cells.sort_unstable();
    let find = |k: usize| cells.binary_search_by_key(&k, |c| c.0).ok();
    let polygon = |k: usize| find(k).and_then(|i| at(cells[i].1).cell(cells[i].2));
    let nodes: Vec<usize> = cells.iter().map(|c| c.0).collect();
    let adjacency = level_adjacency(polygon, &nodes, lv.scale);
    let in_d = |k: usize| find(k).is_some_and(|i| cells[i].1 == d);
    let mut realized = 0;
    let mut elongation = 0.0;
    for &(a, e, j) in &cells {
        if e != d {
            continue;
        }
        if let Some(p) = at(e).cell(j) {
            elongation += aspect(p) - 1.0;
        }
        realized += links.worth(a, |b| adjacency.are_adjacent(a, b) && (!in_d(b) || b > a));
    }
    realized as f64 - lv.np.shape_weight * elongation
}
