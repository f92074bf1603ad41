//! One level being laid out: its diagrams ([`Diagram`]) and a snapshot of
//! their current geometry ([`Snapshot`]): sites, centroids and which cells
//! share an edge across the whole level, which the attraction moves, the swaps
//! and the score all read.
//!
//! The snapshot's adjacency is built without comparing every cell's polygon:
//! inside one diagram, the power diagram already lists each cell's neighbours
//! and their common edge; only cells on their parent's boundary can touch a
//! cousin, and of those only pairs with a cell that moves are compared per
//! snapshot: the pairs of only children, whose cells are their parents' and
//! fixed for the level, are compared once (`super::cross`). Same graph as
//! comparing every boundary cell with [`level_adjacency`], and as the
//! checker's up to round-off at the 1e-6 threshold ([`MIN_SHARED`]).

use super::cross::{CrossCache, CrossPlan, Part};
use super::links::{LevelLinks, Score};
use super::NeighborParams;
use crate::geom::shared_edge::{MIN_SHARED, PERPENDICULAR_TOL};
use crate::geom::{level_adjacency, ConvexPolygon, LevelAdjacency, Point};
use crate::layout::map::MapSimulation;

/// One parent's diagram on the level being laid out.
#[derive(Clone)]
pub(super) enum Diagram {
    /// A parent with one child: the child takes the parent's cell.
    Single {
        child: usize,
        polygon: ConvexPolygon,
    },
    /// A parent with several children.
    Sim {
        children: Vec<usize>,
        sim: Box<MapSimulation>,
    },
}

impl Diagram {
    /// How many children the diagram lays out.
    pub(super) fn len(&self) -> usize {
        match self {
            Diagram::Single { .. } => 1,
            Diagram::Sim { children, .. } => children.len(),
        }
    }

    /// The parent's cell.
    pub(super) fn clip(&self) -> &ConvexPolygon {
        match self {
            Diagram::Single { polygon, .. } => polygon,
            Diagram::Sim { sim, .. } => sim.clip(),
        }
    }

    /// The cell of the `slot`-th child, if it has one.
    pub(super) fn cell(&self, slot: usize) -> Option<&ConvexPolygon> {
        match self {
            Diagram::Single { polygon, .. } => Some(polygon),
            Diagram::Sim { sim, .. } => sim.state().diagram.cells[slot].polygon.as_ref(),
        }
    }

    /// The diagram's area error (0 for an only child).
    pub(super) fn area_error(&self) -> f64 {
        match self {
            Diagram::Single { .. } => 0.0,
            Diagram::Sim { sim, .. } => sim.state().convergence_ratio,
        }
    }
}

/// Current geometry of the level: per level-local index the site, centroid,
/// the diagram it belongs to and its index there; the level's adjacency and
/// the score it gives.
pub(super) struct Snapshot {
    pub(super) site: Vec<Point>,
    pub(super) centroid: Vec<Point>,
    pub(super) diagram: Vec<usize>,
    pub(super) slot: Vec<usize>,
    pub(super) adjacency: LevelAdjacency,
    pub(super) score: Score,
    /// Largest area error of the level's diagrams.
    pub(super) area_error: f64,
}

/// What every step of one level's layout reads: its constraints, the length
/// scale adjacency is judged at, the settings.
pub(super) struct LevelCtx<'a> {
    pub(super) links: &'a LevelLinks,
    /// The layout's length scale (the root's bounding-box diagonal), which the
    /// adjacency threshold is relative to.
    pub(super) scale: f64,
    pub(super) np: &'a NeighborParams,
    /// What of the level's adjacency cannot change, made on its first snapshot.
    cross: CrossCache,
}

impl<'a> LevelCtx<'a> {
    pub(super) fn new(links: &'a LevelLinks, scale: f64, np: &'a NeighborParams) -> Self {
        Self {
            links,
            scale,
            np,
            cross: CrossCache::default(),
        }
    }

    /// The snapshot of `diagrams`.
    pub(super) fn snapshot(&self, diagrams: &[Diagram]) -> Snapshot {
        snapshot(diagrams, self.links, self.scale, self.np, &self.cross)
    }
}

fn snapshot(
    diagrams: &[Diagram],
    links: &LevelLinks,
    scale: f64,
    np: &NeighborParams,
    cross: &CrossCache,
) -> Snapshot {
    let parts: Vec<Part<'_>> = diagrams
        .iter()
        .map(|d| match d {
            Diagram::Single { child, polygon } => Part::Single {
                child: *child,
                polygon,
            },
            Diagram::Sim { sim, .. } => Part::Sim { clip: sim.clip() },
        })
        .collect();
    let plan = cross.plan(&parts, links, scale, aspect);
    let mut walk = Walk::new(links.nodes.len(), scale);
    for (d, dg) in diagrams.iter().enumerate() {
        walk.area_error = walk.area_error.max(dg.area_error());
        match dg {
            Diagram::Single { child, .. } => {
                let (c, a) = plan.single(d).expect("the plan fits the diagrams");
                walk.single(links.local[*child], d, c, a);
            }
            Diagram::Sim { children, sim } => {
                walk.sim(d, children, sim, links, &plan, diagrams.len() > 1);
            }
        }
    }
    let Walk {
        site,
        centroid,
        diagram,
        slot,
        present,
        mut pairs,
        boundary,
        within_reach,
        elongation,
        area_error,
        ..
    } = walk;
    if diagrams.len() > 1 {
        let cell = |k: usize| diagrams[diagram[k]].cell(slot[k]);
        let cross = if within_reach {
            plan.cross_pairs(cell, &boundary, &diagram)
        } else {
            every_cross_pair(diagrams, &boundary, &diagram, &slot, links, scale)
        };
        #[cfg(test)]
        {
            let every = || every_cross_pair(diagrams, &boundary, &diagram, &slot, links, scale);
            tests::check_cross(&cross, every, diagrams, &diagram, within_reach);
        }
        pairs.extend(cross);
    }
    let adjacency = LevelAdjacency::from_pairs(present, pairs);
    // From the plan only when its fixed pairs are the adjacency's pairs of
    // only children, which the full comparison gives too, but is not asked.
    let realized = if within_reach {
        plan.realized(&adjacency, &diagram)
    } else {
        links.realized(&adjacency)
    };
    #[cfg(test)]
    {
        assert_eq!(realized, links.realized(&adjacency), "realised constraints");
    }
    let score = Score {
        realized,
        elongation,
        shape_weight: np.shape_weight,
    };
    Snapshot {
        site,
        centroid,
        diagram,
        slot,
        adjacency,
        score,
        area_error,
    }
}

/// What [`snapshot`] gathers diagram by diagram, in level-local indices: each
/// cell's site, centroid, diagram and slot, the cells present, the pairs
/// adjacent within a diagram, and the cells of moving diagrams on their
/// parent's boundary (whether each lies in its diagram's reach: else every
/// pair across diagrams is compared, see `cross`).
struct Walk {
    site: Vec<Point>,
    centroid: Vec<Point>,
    diagram: Vec<usize>,
    slot: Vec<usize>,
    present: Vec<usize>,
    pairs: Vec<(usize, usize)>,
    boundary: Vec<usize>,
    within_reach: bool,
    elongation: f64,
    area_error: f64,
    /// Shortest shared edge that makes two cells adjacent.
    threshold: f64,
    /// How near a cell's corner must be to its parent's boundary to count as on it.
    on_edge: f64,
}

impl Walk {
    fn new(m: usize, scale: f64) -> Self {
        Walk {
            site: vec![Point::ZERO; m],
            centroid: vec![Point::ZERO; m],
            diagram: vec![0; m],
            slot: vec![0; m],
            present: Vec::with_capacity(m),
            pairs: Vec::new(),
            boundary: Vec::new(),
            within_reach: true,
            elongation: 0.0,
            area_error: 0.0,
            threshold: MIN_SHARED * scale,
            on_edge: 10.0 * PERPENDICULAR_TOL * scale,
        }
    }

    /// An only child `k` of diagram `d`: its parent's cell, with centroid `c`
    /// and aspect `a`.
    fn single(&mut self, k: usize, d: usize, c: Point, a: f64) {
        self.site[k] = c;
        self.centroid[k] = c;
        self.diagram[k] = d;
        self.present.push(k);
        self.elongation += a - 1.0;
    }

    /// The cells of a moving diagram `d`; `shared` when the level has other
    /// diagrams, whose cells may touch these across the parent's boundary.
    fn sim(
        &mut self,
        d: usize,
        children: &[usize],
        sim: &MapSimulation,
        links: &LevelLinks,
        plan: &CrossPlan,
        shared: bool,
    ) {
        let state = sim.state();
        let clip = sim.clip();
        for (j, c) in children.iter().enumerate() {
            let k = links.local[*c];
            let cell = &state.diagram.cells[j];
            self.site[k] = state.sites[j].position;
            self.centroid[k] = cell.centroid;
            self.diagram[k] = d;
            self.slot[k] = j;
            let Some(polygon) = &cell.polygon else {
                continue;
            };
            self.present.push(k);
            self.elongation += aspect(polygon) - 1.0;
            for nb in &cell.neighbors {
                if nb.site > j && nb.edge[0].distance(nb.edge[1]) >= self.threshold {
                    let o = links.local[children[nb.site]];
                    self.pairs.push((k.min(o), k.max(o)));
                }
            }
            if shared
                && polygon
                    .points()
                    .iter()
                    .any(|v| clip.boundary_distance(*v) <= self.on_edge)
            {
                self.boundary.push(k);
                self.within_reach &= plan.holds(d, polygon);
            }
        }
    }
}

/// The level's adjacent pairs across diagrams by comparing every cell on its
/// parent's boundary (`moving`, cells of moving diagrams) and every only
/// child with each other: what [`CrossPlan::cross_pairs`] gives without the
/// comparisons that cannot count or cannot change.
///
/// [`CrossPlan::cross_pairs`]: super::cross::CrossPlan::cross_pairs
fn every_cross_pair(
    diagrams: &[Diagram],
    moving: &[usize],
    diagram: &[usize],
    slot: &[usize],
    links: &LevelLinks,
    scale: f64,
) -> Vec<(usize, usize)> {
    let mut boundary = moving.to_vec();
    for d in diagrams {
        if let Diagram::Single { child, .. } = d {
            boundary.push(links.local[*child]);
        }
    }
    let cell = |k: usize| diagrams[diagram[k]].cell(slot[k]);
    let all = level_adjacency(cell, &boundary, scale);
    all.pairs()
        .iter()
        .copied()
        .filter(|&(a, b)| diagram[a] != diagram[b])
        .collect()
}

/// Bounding-box aspect ratio of a cell (long side over short, the checker's
/// `aspect_ratio_mean` term); 1 for a degenerate box.
pub(super) fn aspect(polygon: &ConvexPolygon) -> f64 {
    let (lo, hi) = polygon.bbox();
    let (w, h) = (hi.x - lo.x, hi.y - lo.y);
    if w > 0.0 && h > 0.0 {
        w.max(h) / w.min(h)
    } else {
        1.0
    }
}

/// The level's current cells, for a [`Frame`](crate::layout::Frame).
pub(super) fn frame_cells(diagrams: &[Diagram]) -> Vec<(usize, ConvexPolygon)> {
    let mut cells = Vec::new();
    for d in diagrams {
        match d {
            Diagram::Single { child, polygon } => cells.push((*child, polygon.clone())),
            Diagram::Sim { children, sim } => {
                let state = sim.state();
                for (c, cell) in children.iter().zip(&state.diagram.cells) {
                    if let Some(p) = &cell.polygon {
                        cells.push((*c, p.clone()));
                    }
                }
            }
        }
    }
    cells
}

/// Settles a diagram's areas with its sites held in place, to `target` or
/// for `np.settle_iterations` weight steps at most.
pub(super) fn settle_to(d: &mut Diagram, np: &NeighborParams, target: f64) {
    if let Diagram::Sim { sim, .. } = d {
        for _ in 0..np.settle_iterations {
            let before = sim.state().convergence_ratio;
            if before <= target {
                break;
            }
            let after = sim.settle_weights();
            // A step that found no better weights keeps them, and the next
            // would search from the same weights to the same end.
            if after <= target || after >= before {
                break;
            }
        }
    }
}

/// [`settle_to`] the run's own area target.
pub(super) fn settle(d: &mut Diagram, np: &NeighborParams) {
    if let Diagram::Sim { sim, .. } = d {
        let target = sim.area_target();
        settle_to(d, np, target);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Config, DatasetConfig};
    use crate::geom::shared_edge::shared_length_calls;
    use crate::layout::map::MapSettings;
    use crate::layout::{compute, Request};
    use crate::rng::Rng;
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec, SimilarityHint};
    use std::cell::Cell;
    use std::path::Path;

    /// What [`check_cross`] saw on this thread.
    #[derive(Clone, Copy, Debug, Default)]
    struct Seen {
        /// Snapshots of several diagrams, checked.
        snapshots: usize,
        /// Of those, made from the level's plan (not the full comparison).
        planned: usize,
        /// With a pair of two only children.
        fixed: usize,
        /// With a pair that has a cell of a moving diagram.
        moving: usize,
    }

    thread_local! {
        static SEEN: Cell<Seen> = Cell::new(Seen::default());
    }

    /// Every snapshot of a test build: the pairs across diagrams must be
    /// exactly those of comparing every boundary cell and every only child
    /// with each other, as the snapshot did before the plan.
    pub(super) fn check_cross(
        cross: &[(usize, usize)],
        every: impl FnOnce() -> Vec<(usize, usize)>,
        diagrams: &[Diagram],
        diagram: &[usize],
        planned: bool,
    ) {
        let before = shared_length_calls();
        let want = every();
        // The reference's own comparisons are not the snapshot's.
        shared_length_calls_rewind(before);
        let mut got = cross.to_vec();
        got.sort_unstable();
        got.dedup();
        assert_eq!(got, want, "pairs across diagrams");
        let single = |k: usize| matches!(diagrams[diagram[k]], Diagram::Single { .. });
        let fixed = want.iter().any(|&(a, b)| single(a) && single(b));
        let moves = want.iter().any(|&(a, b)| !(single(a) && single(b)));
        SEEN.with(|s| {
            let mut v = s.get();
            v.snapshots += 1;
            v.planned += usize::from(planned);
            v.fixed += usize::from(fixed);
            v.moving += usize::from(moves);
            s.set(v);
        });
    }

    fn shared_length_calls_rewind(to: usize) {
        crate::geom::shared_edge::set_shared_length_calls(to);
    }

    /// Runs `f` and returns what [`check_cross`] saw meanwhile.
    fn seen_during(f: impl FnOnce()) -> Seen {
        SEEN.with(|s| s.set(Seen::default()));
        f();
        SEEN.with(Cell::get)
    }

    fn lay_out(ds: &Dataset, request: &Request) {
        let computed = compute(ds, request).expect("layout");
        assert_eq!(computed.layout.cells.len(), computed.dataset.len());
    }

    /// A deep tree with leaves at every depth from 1 to 6 (so virtual copies
    /// down to the deepest level, paper §4), only children among the real
    /// folders too, and every leaf linked to a few others.
    fn deep_tree(seed: u64, leaves: usize) -> Dataset {
        let mut rng = Rng::new(seed);
        let mut b = DatasetBuilder::new();
        b.similarity_hint(SimilarityHint::NeighborList);
        b.add(NodeSpec::new("r"));
        // Folders: each under a random earlier one, at most depth 5.
        let mut folders: Vec<(String, usize)> = vec![("r".to_string(), 0)];
        for f in 0..leaves / 4 {
            let (parent, depth) = folders[(rng.next_f64() * folders.len() as f64) as usize].clone();
            if depth >= 5 {
                continue;
            }
            let id = format!("f{f}");
            b.add(NodeSpec::new(id.clone()).parent(parent));
            folders.push((id, depth + 1));
        }
        let ids: Vec<String> = (0..leaves).map(|i| format!("l{i}")).collect();
        for (i, id) in ids.iter().enumerate() {
            // Every folder gets a leaf first, so none is empty.
            let (parent, _) = if i < folders.len() {
                folders[i].clone()
            } else {
                folders[(rng.next_f64() * folders.len() as f64) as usize].clone()
            };
            let mut spec = NodeSpec::new(id.clone())
                .parent(parent)
                .weight(1.0 + (rng.next_f64() * 20.0).floor());
            for _ in 0..3 {
                let other = (rng.next_f64() * leaves as f64) as usize;
                if other != i {
                    spec = spec.relation(ids[other].clone());
                }
            }
            b.add(spec);
        }
        b.build().expect("a valid tree")
    }

    /// Issue 23, items 2 and 5: the pairs a snapshot compares per tick are
    /// those that can change; the level's adjacency stays the one every
    /// boundary cell compared with every other gives. Checked in every
    /// snapshot of deep trees with virtual copies (`check_cross`).
    #[test]
    fn snapshot_pairs_are_the_full_comparison_on_deep_trees_with_copies() {
        for seed in [1, 2, 3] {
            let ds = deep_tree(seed, 240);
            let seen = seen_during(|| lay_out(&ds, &Request::default()));
            assert!(seen.planned > 0 && seen.planned == seen.snapshots, "{seen:?}");
            assert!(seen.fixed > 0 && seen.moving > 0, "{seen:?}");
        }
    }

    /// The same on the paper's files (copies in the unbalanced ones).
    #[test]
    fn snapshot_pairs_are_the_full_comparison_on_the_paper_data() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/paper");
        let files = [
            "2_level_4_cousin_constraints.json",
            "cifar10.json",
            "country_pop_50M_AUS.json",
            "flare.json",
            "imdb_100_genre_sim_2child.json",
            "language.json",
            "olympia.json",
            "syntheticPoints_10nodes_2components.json",
            "syntheticPoints_10nodes_all_attracted_to_1.json",
            "syntheticPoints_4.json",
            "syntheticPoints_5nodes_fully_connected.json",
        ]
        .map(|f| dir.join(f));
        let mut all = Seen::default();
        for file in files {
            let ds = crate::pipeline::load(&DatasetConfig::hierarchy_file(&file, None))
                .expect("a paper file loads");
            let seen = seen_during(|| lay_out(&ds, &Request::default()));
            all.snapshots += seen.snapshots;
            all.fixed += seen.fixed;
            all.moving += seen.moving;
        }
        assert!(all.fixed > 0 && all.moving > 0, "{all:?}");
    }

    /// The same on the committed real datasets, with their own configs.
    #[test]
    fn snapshot_pairs_are_the_full_comparison_on_the_real_data() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real");
        let mut all = Seen::default();
        for name in ["python-stdlib", "debian-packages", "man-pages", "usr-bin"] {
            let config = Config::from_path(&root.join(name).join("nptreemap.yaml"))
                .expect("the dataset's config");
            for d in &config.datasets {
                let ds = crate::pipeline::load(d).expect("the dataset loads");
                let seen = seen_during(|| lay_out(&ds, &config.request(d)));
                all.snapshots += seen.snapshots;
                all.moving += seen.moving;
            }
        }
        assert!(all.moving > 0, "{all:?}");
    }

    /// A level of `n` × `n` square parent cells, all only children but one
    /// parent (`busy`) with `k` children.
    fn grid_level(n: usize, busy: usize, k: usize) -> (Dataset, Vec<Diagram>, Vec<usize>) {
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("r"));
        for p in 0..n * n {
            b.add(NodeSpec::new(format!("p{p}")).parent("r"));
            let children = if p == busy { k } else { 1 };
            for c in 0..children {
                b.add(NodeSpec::new(format!("p{p}c{c}")).parent(format!("p{p}")));
            }
        }
        let ds = b.build().expect("a valid tree");
        let mut level = Vec::new();
        let mut diagrams = Vec::new();
        for p in 0..n * n {
            let parent = ds.find(&format!("p{p}")).expect("parent");
            let children = ds.node(parent).children.clone();
            level.extend(&children);
            let clip = ConvexPolygon::rectangle((p % n) as f64, (p / n) as f64, 1.0, 1.0)
                .expect("a square");
            diagrams.push(if children.len() == 1 {
                Diagram::Single {
                    child: children[0],
                    polygon: clip,
                }
            } else {
                let mut rng = Rng::new(7);
                let (x, y) = ((p % n) as f64, (p / n) as f64);
                let sites = (0..children.len())
                    .map(|_| Point::new(x + 0.1 + 0.8 * rng.next_f64(), y + 0.1 + 0.8 * rng.next_f64()))
                    .collect();
                let targets = vec![1.0 / children.len() as f64; children.len()];
                let settings = MapSettings {
                    convergence_ratio: 0.01,
                    max_iterations: 50,
                    min_iterations: 0,
                };
                let sim = MapSimulation::new(clip, targets, sites, None, settings, rng);
                Diagram::Sim {
                    children,
                    sim: Box::new(sim),
                }
            });
        }
        (ds, diagrams, level)
    }

    /// Issue 23, item 5: a tick costs what changes. On a level of 899 only
    /// children around one moving diagram of 5 cells, a snapshot after the
    /// first compares only the moving cells with the 8 parent cells around
    /// theirs (at most 5 × 8 polygon pairs), not the 899 fixed cells with each
    /// other (thousands of pairs every tick before), and its adjacency is the
    /// full comparison's.
    #[test]
    fn a_snapshot_compares_only_pairs_that_can_change() {
        let n = 30;
        let busy = 15 * n + 15;
        let (ds, mut diagrams, level) = grid_level(n, busy, 5);
        let links = LevelLinks::new(&ds, &level, &[], 2);
        let np = NeighborParams::default();
        let scale = (2.0 * (n * n) as f64).sqrt();
        let lv = LevelCtx::new(&links, scale, &np);
        let first = lv.snapshot(&diagrams);
        // The fixed cells' grid: 2 n (n − 1) shared sides, less the 4 sides
        // of the busy parent's cell, whose children take them.
        let fixed = (0..first.adjacency.pairs().len())
            .filter(|&p| {
                let (a, b) = first.adjacency.pairs()[p];
                first.diagram[a] != busy && first.diagram[b] != busy
            })
            .count();
        assert_eq!(fixed, 2 * n * (n - 1) - 4);
        for _ in 0..3 {
            if let Diagram::Sim { sim, .. } = &mut diagrams[busy] {
                sim.lloyd_tick();
            }
            let before = shared_length_calls();
            let snap = lv.snapshot(&diagrams);
            let calls = shared_length_calls() - before;
            assert!(calls <= 5 * 8, "{calls} polygon pairs compared");
            // Every moving cell touches the busy parent's boundary or a sibling;
            // together they cover its 4 sides, each shared with a fixed cell.
            let across = snap
                .adjacency
                .pairs()
                .iter()
                .filter(|&&(a, b)| (snap.diagram[a] == busy) != (snap.diagram[b] == busy))
                .count();
            assert!(across >= 4, "{across}");
        }
    }
}
