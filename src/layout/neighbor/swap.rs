//! Swaps of same-parent cells (method-reference §4.4): greedy rounds whose gains
//! are read off the current adjacency (exchanging two sites with their weights
//! exchanges their cells, so the gain is exact for the geometry at hand), and
//! on small levels an exhaustive polish that measures each swap after settling
//! the areas, judged locally: only the one diagram is settled and only the pairs
//! touching its cells are counted, never the whole level.

use rayon::prelude::*;

use super::level::{aspect, settle, Diagram, LevelCtx, Snapshot};
use super::links::LIFTED_WEIGHT;
use crate::geom::shared_edge::{MIN_SHARED, PERPENDICULAR_TOL};
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
    let snap = lv.snapshot(diagrams);
    let pairs = plan_swaps(diagrams, &snap, lv, max_ratio);
    apply_swaps(diagrams, &snap, &pairs);
    pairs.len()
}

/// The swaps of one greedy round on the geometry of `snap`, as level-local
/// pairs `(a, b)`, `a < b`: best gain first, no cell twice, no two swaps
/// next to each other.
///
/// The gain of exchanging `a` and `b` is what `a`'s partners are worth around
/// `b`'s cell plus `b`'s around `a`'s, less what they are worth where they are.
/// The first term is summed over the partners' neighbour lists (each partner
/// `t` of `a` adds its worth to every cell next to it), so a cell's candidates
/// cost one pass over its partners' neighbours instead of one adjacency test
/// per partner per candidate: on a flat diagram of 10,000 cells the search
/// was a fifth of the whole layout.
pub(super) fn plan_swaps(
    diagrams: &[Diagram],
    snap: &Snapshot,
    lv: &LevelCtx<'_>,
    max_ratio: f64,
) -> Vec<(usize, usize)> {
    let links = lv.links;
    let adj = &snap.adjacency;
    let n = links.nodes.len();
    // What node x's partners (own and lifted) adjacent to the cell at `at` are worth.
    let realized = |x: usize, at: usize| -> i64 {
        links.worth(x, |t| t != at && adj.are_adjacent(t, at)) as i64
    };
    let here: Vec<i64> = (0..n).map(|a| realized(a, a)).collect();
    let mut around = vec![0i64; n];
    let mut touched: Vec<usize> = Vec::new();
    let mut candidates: Vec<(i64, usize, usize)> = Vec::new();
    for a in 0..n {
        if matches!(diagrams[snap.diagram[a]], Diagram::Single { .. }) {
            continue;
        }
        // Only cells next to a partner of `a` can gain by taking a's node.
        let own = links.links[a].iter().map(|&(t, _)| (t, 1i64));
        let deep = links.lifted[a]
            .iter()
            .map(|&(t, k)| (t, (LIFTED_WEIGHT * k) as i64));
        for (t, w) in own.chain(deep) {
            for &b in adj.neighbors(t) {
                if b != a && snap.diagram[b] == snap.diagram[a] {
                    if around[b] == 0 {
                        touched.push(b);
                    }
                    around[b] += w;
                }
            }
        }
        for &b in &touched {
            let gain = around[b] + realized(b, a) - here[a] - here[b];
            if gain > 0 && target_ratio(&diagrams[snap.diagram[a]], snap.slot[a], snap.slot[b]) <= max_ratio {
                candidates.push((gain, a.min(b), a.max(b)));
            }
        }
        for b in touched.drain(..) {
            around[b] = 0;
        }
    }
    candidates.sort_by(|p, q| q.0.cmp(&p.0).then(p.1.cmp(&q.1)).then(p.2.cmp(&q.2)));
    candidates.dedup();
    let mut dirty = vec![false; n];
    let mut chosen = Vec::new();
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
        chosen.push((a, b));
    }
    chosen
}

/// Exchanges the sites (with their weights) of each level-local pair of
/// `pairs`, all in one diagram each, one power diagram per diagram touched.
pub(super) fn apply_swaps(diagrams: &mut [Diagram], snap: &Snapshot, pairs: &[(usize, usize)]) {
    let mut per_diagram: Vec<Vec<(usize, usize)>> = vec![Vec::new(); diagrams.len()];
    for &(a, b) in pairs {
        per_diagram[snap.diagram[a]].push((snap.slot[a], snap.slot[b]));
    }
    diagrams
        .par_iter_mut()
        .zip(per_diagram.par_iter())
        .for_each(|(d, pairs)| {
            if let Diagram::Sim { sim, .. } = d {
                sim.swap_sites(pairs);
            }
        });
}

/// The swaps of `pairs` (made on the geometry of `before`, then settled)
/// that did not pay locally: those whose neighbourhood realises no more than
/// before. A swap's neighbourhood is its two cells and their neighbours before
/// and after; what it realises is every constraint with an end there, counted
/// once, read from `before` and from the settled diagram's own power cells
/// (its exact adjacency). Partners in other diagrams are read from `before`
/// with the exchange applied (each node takes the other's place on the
/// parent's boundary), so no whole-level adjacency is built to judge.
pub(super) fn unpaid_swaps(
    diagrams: &[Diagram],
    before: &Snapshot,
    pairs: &[(usize, usize)],
    lv: &LevelCtx<'_>,
) -> Vec<(usize, usize)> {
    let links = lv.links;
    let threshold = MIN_SHARED * lv.scale;
    // Where each swapped node's cell was before the round.
    let mut place: Vec<usize> = (0..links.nodes.len()).collect();
    for &(a, b) in pairs {
        place.swap(a, b);
    }
    // Same-diagram neighbours of a level-local node after the round.
    let after = |x: usize| -> Vec<usize> {
        let d = before.diagram[x];
        match &diagrams[d] {
            Diagram::Sim { children, sim } => sim.state().diagram.cells[before.slot[x]]
                .neighbors
                .iter()
                .filter(|nb| nb.edge[0].distance(nb.edge[1]) >= threshold)
                .map(|nb| links.local[children[nb.site]])
                .collect(),
            Diagram::Single { .. } => Vec::new(),
        }
    };
    pairs
        .iter()
        .copied()
        .filter(|&(a, b)| {
            let mut region: Vec<usize> = vec![a, b];
            let mut next: Vec<(usize, Vec<usize>)> = Vec::new();
            for x in [a, b] {
                region.extend_from_slice(before.adjacency.neighbors(x));
            }
            for x in [a, b] {
                let nx = after(x);
                region.extend_from_slice(&nx);
            }
            region.sort_unstable();
            region.dedup();
            for &x in &region {
                next.push((x, after(x)));
            }
            let in_region = |x: usize| region.binary_search(&x).is_ok();
            let adjacent_after = |x: usize, t: usize| -> bool {
                if before.diagram[t] == before.diagram[x] {
                    match next.binary_search_by_key(&x, |e| e.0) {
                        Ok(i) => next[i].1.contains(&t),
                        Err(_) => false,
                    }
                } else {
                    before.adjacency.are_adjacent(place[x], place[t])
                }
            };
            let count = |adjacent: &dyn Fn(usize, usize) -> bool| -> usize {
                region
                    .iter()
                    .map(|&x| links.worth(x, |t| (!in_region(t) || t > x) && adjacent(x, t)))
                    .sum()
            };
            let was = count(&|x, t| before.adjacency.are_adjacent(x, t));
            let now = count(&adjacent_after);
            now <= was
        })
        .collect()
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
