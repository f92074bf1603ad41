//! Swaps of same-parent cells (method-reference §4.4): greedy rounds whose gains
//! are read off the current adjacency (exchanging two sites with their weights
//! exchanges their cells, so the gain is exact for the geometry at hand), and
//! on small levels an exhaustive polish that measures each swap after settling
//! the areas, judged locally: only the one diagram is settled and only the pairs
//! touching its cells are counted, never the whole level. [`pays`] judges any
//! move of a few cells the same way, from its neighbourhood.

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

/// Did moving the cells of `moved` (level-local nodes, on the geometry of
/// `before`, then settled) pay locally: does their neighbourhood realise
/// more than before? The neighbourhood is the moved cells and their
/// neighbours before and after; what it realises is every constraint with an
/// end there, counted once, read from `before` and from the settled
/// diagram's own power cells (its exact adjacency). Partners in other
/// diagrams are read from `before`, each node at `place[node]`'s cell there
/// (the cell it took over), so no whole-level adjacency is built to judge.
pub(super) fn pays(
    diagrams: &[Diagram],
    before: &Snapshot,
    moved: &[usize],
    place: &[usize],
    lv: &LevelCtx<'_>,
) -> bool {
    let links = lv.links;
    let threshold = MIN_SHARED * lv.scale;
    // Same-diagram neighbours of a level-local node after the round.
    let after = |x: usize| -> Vec<usize> {
        match &diagrams[before.diagram[x]] {
            Diagram::Sim { children, sim } => {
                let mut n: Vec<usize> = sim.state().diagram.cells[before.slot[x]]
                    .neighbors
                    .iter()
                    .filter(|nb| nb.edge[0].distance(nb.edge[1]) >= threshold)
                    .map(|nb| links.local[children[nb.site]])
                    .collect();
                n.sort_unstable();
                n
            }
            Diagram::Single { .. } => Vec::new(),
        }
    };
    let mut region: Vec<usize> = moved.to_vec();
    for &x in moved {
        region.extend_from_slice(before.adjacency.neighbors(x));
        region.extend(after(x));
    }
    region.sort_unstable();
    region.dedup();
    let next: Vec<Vec<usize>> = region.iter().map(|&x| after(x)).collect();
    let in_region = |x: usize| region.binary_search(&x).is_ok();
    let adjacent_after = |i: usize, x: usize, t: usize| -> bool {
        if before.diagram[t] == before.diagram[x] {
            next[i].binary_search(&t).is_ok()
        } else {
            before.adjacency.are_adjacent(place[x], place[t])
        }
    };
    let mut was = 0;
    let mut now = 0;
    for (i, &x) in region.iter().enumerate() {
        let counted = |t: usize| !in_region(t) || t > x;
        was += links.worth(x, |t| counted(t) && before.adjacency.are_adjacent(x, t));
        now += links.worth(x, |t| counted(t) && adjacent_after(i, x, t));
    }
    now > was
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::ConvexPolygon;
    use crate::layout::map::{MapSettings, MapSimulation};
    use super::super::links::LevelLinks;
    use super::super::NeighborParams;
    use crate::rng::Rng;

    /// Three equal cells in a row (nodes 0, 1, 2 left to right) and the
    /// constraints `pairs` between them.
    fn row(pairs: &[(usize, usize)]) -> (Vec<Diagram>, LevelLinks) {
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 6.0, 2.0).expect("rectangle");
        let positions = vec![Point::new(1.0, 1.0), Point::new(3.0, 1.0), Point::new(5.0, 1.0)];
        let settings = MapSettings {
            convergence_ratio: 0.01,
            max_iterations: 10,
            min_iterations: 0,
        };
        let sim = MapSimulation::new(clip, vec![4.0; 3], positions, None, settings, Rng::new(1));
        let mut links = vec![Vec::new(); 3];
        for &(a, b) in pairs {
            links[a].push((b, 100));
            links[b].push((a, 100));
        }
        let level = LevelLinks {
            local: vec![0, 1, 2],
            nodes: vec![0, 1, 2],
            links,
            lifted: vec![Vec::new(); 3],
        };
        let d = Diagram::Sim {
            children: vec![0, 1, 2],
            sim: Box::new(sim),
        };
        (vec![d], level)
    }

    fn ctx<'a>(links: &'a LevelLinks, np: &'a NeighborParams) -> LevelCtx<'a> {
        LevelCtx::new(links, 40f64.sqrt(), np)
    }

    #[test]
    fn the_best_swap_is_planned_and_its_neighbour_left_alone() {
        // 0 and 2 want to touch: moving either into the middle realises it.
        let (diagrams, links) = row(&[(0, 2)]);
        let np = NeighborParams::default();
        let lv = ctx(&links, &np);
        let snap = lv.snapshot(&diagrams);
        // Both (0, 1) and (1, 2) gain one constraint; ties go to the lower
        // pair, and the other shares cell 1 with it.
        assert_eq!(plan_swaps(&diagrams, &snap, &lv, f64::INFINITY), vec![(0, 1)]);
        // Nothing to gain when the pair already touches.
        let (diagrams, links) = row(&[(0, 1)]);
        let lv = ctx(&links, &np);
        let snap = lv.snapshot(&diagrams);
        assert!(plan_swaps(&diagrams, &snap, &lv, f64::INFINITY).is_empty());
    }

    #[test]
    fn a_swap_pays_only_when_its_neighbourhood_realises_more() {
        let np = NeighborParams::default();
        for (pairs, swap, expected) in [
            // Brings 0 and 2 together: pays.
            (vec![(0, 2)], (1, 2), true),
            // Separates 0 and 1 and joins nothing: does not pay.
            (vec![(0, 1)], (1, 2), false),
            // Separates 0-1 but joins 0-2: even, does not pay.
            (vec![(0, 1), (0, 2)], (1, 2), false),
        ] {
            let (mut diagrams, links) = row(&pairs);
            let lv = ctx(&links, &np);
            let before = lv.snapshot(&diagrams);
            apply_swaps(&mut diagrams, &before, &[swap]);
            // Each swapped node now sits in the other's old cell.
            let mut place = vec![0, 1, 2];
            place.swap(swap.0, swap.1);
            let paid = pays(&diagrams, &before, &[swap.0, swap.1], &place, &lv);
            assert_eq!(paid, expected, "{pairs:?} swapping {swap:?}");
        }
    }
}
