//! Similarity-driven layouts, level by level from the root down: the paper's
//! initialisation (a CVT per parent, Kuhn–Munkres matching of projected nodes to
//! CVT sites, greedy swaps; method-reference §4), its two baselines (§6.2), and
//! the joint per-level optimisation of Algorithms 1 and 2 (§5). This file is the
//! level loop; each stage has its own file:
//! - [`params`]: the settings and the distance rules;
//! - `links`: a level's constraints and what an arrangement scores;
//! - `level`: a level's diagrams and the snapshot every step reads;
//! - `cross`: what of the snapshot's adjacency across diagrams is fixed for
//!   the level (only children's pairs), computed once;
//! - `start`: CVT, matching and the baselines' starts;
//! - `swap`: greedy swap rounds and the small levels' exhaustive polish;
//! - `attract`: the attraction moves;
//! - `optimize`: our schedule (progress-driven tick budget, relaxation, polish);
//! - `prototype`: the paper prototype's schedule;
//! - `secure`: repairs and fallbacks, so that a level never fails.
//!
//! Where this departs from the prototype, and why:
//! - Cells track their target areas during the whole optimisation (a Newton
//!   weight step every tick, see `super::map`) instead of growing in the last
//!   30% of ticks: growth at the end undoes neighbourhoods the attraction has
//!   just built. The final weight-only settling keeps the arrangement.
//! - Distance constants are relative to the level's typical cell size instead of
//!   screen pixels (method-reference §10 row 1), so the method behaves the same
//!   on any canvas and at any depth.
//! - Diagrams of a level read cousins at their start-of-round positions (§5.2),
//!   so they are independent within a round and run in parallel.
//! - A level stops when its score plateaus instead of after a fixed 150 ticks,
//!   and every site is pulled towards its centroid while it moves (round
//!   cells; issue 12).

mod attract;
mod cross;
mod delaunay;
mod flip;
mod level;
mod links;
mod optimize;
mod params;
mod prototype;
mod secure;
mod start;
mod swap;

use rayon::prelude::*;

use self::level::{frame_cells, settle, Diagram, LevelCtx};
use self::links::LevelLinks;
use self::optimize::optimize_level;
use self::params::{prototype_root_area, Distances};
use self::prototype::optimize_prototype;
use self::secure::{retarget, secure_level};
use self::start::{init_diagram, sim_targets, starts_for};
use super::frames::{Frame, Recorder};
use super::map::MapSettings;
use super::method::Method;
use super::progress::{Monitor, Progress};
use super::treemap::{divide, finish, single_child, sliver, Division};
use super::{Layout, LayoutCell, LayoutError, Params, Report};
use crate::geom::{ConvexPolygon, Point};
use crate::neighborhood::{projection, Constraint};
use nptreemap_formats::Dataset;

pub use params::NeighborParams;

/// Candidates per level followed down the tree when looking ahead.
const LOOKAHEAD_CANDIDATES: usize = 3;

/// 2-D positions for every node of `dataset`, in any scale: PCA of the
/// feature vectors when every node has one of the same length and kind (after
/// `neighborhood::prepare` internal nodes have the mean of their
/// children), else classical MDS of `1 − similarity`.
pub fn projection_of(dataset: &Dataset, similarity: impl Fn(usize, usize) -> f64) -> Vec<Point> {
    let nodes = dataset.nodes();
    let features: Vec<_> = nodes.iter().map(|n| n.features.as_ref()).collect();
    projection::pca_of_features(&features).unwrap_or_else(|| {
        projection::classical_mds_2d(|a, b| 1.0 - similarity(a, b), nodes.len())
    })
}

/// Lays out a prepared dataset (uniform depth) with a similarity-driven method.
/// `constraints` are those of `neighborhood::build_constraints`;
/// `projection` has one point per node (see [`projection_of`]).
#[cfg(any(test, feature = "internals"))]
pub fn layout_similar(
    dataset: &Dataset,
    constraints: &[Constraint],
    projection: &[Point],
    method: Method,
    params: &Params,
    np: &NeighborParams,
) -> Result<(Layout, Report), LayoutError> {
    layout_similar_with(
        dataset,
        constraints,
        projection,
        method,
        params,
        np,
        &Monitor::silent(),
    )
}

/// [`layout_similar`] reporting to `monitor`, which may stop it.
pub(crate) fn layout_similar_with(
    dataset: &Dataset,
    constraints: &[Constraint],
    projection: &[Point],
    method: Method,
    params: &Params,
    np: &NeighborParams,
    monitor: &Monitor<'_>,
) -> Result<(Layout, Report), LayoutError> {
    params.validate()?;
    let root_polygon = params.outline.polygon(params.canvas)?;
    let mut cells: Vec<Option<LayoutCell>> = vec![None; dataset.len()];
    cells[dataset.root()] = Some(LayoutCell {
        site: root_polygon.centroid(),
        power_weight: 0.0,
        polygon: root_polygon.clone(),
    });
    let root_box = root_polygon.bbox();
    let ctx = Context {
        dataset,
        constraints,
        projection,
        method,
        params,
        np,
        root_box,
        scale: (root_box.1 - root_box.0).length(),
        settings: MapSettings {
            convergence_ratio: params.convergence_ratio,
            max_iterations: params.max_iterations,
            min_iterations: params.min_iterations.min(params.max_iterations),
        },
        lookahead: method == Method::Neighbor
            && !np.prototype
            && dataset.len() <= np.lookahead_max_nodes,
        prototype_scale: (root_polygon.area() / prototype_root_area()).sqrt(),
        monitor,
    };
    let (_, cells, mut report, error_sum) = descend(&ctx, 0, cells)?;
    report.set_mean(error_sum);
    Ok((finish(dataset, params.canvas, cells), report))
}

/// Everything a level needs that does not change from level to level.
struct Context<'a> {
    dataset: &'a Dataset,
    constraints: &'a [Constraint],
    projection: &'a [Point],
    method: Method,
    params: &'a Params,
    np: &'a NeighborParams,
    root_box: (Point, Point),
    /// The layout's length scale: the root's bounding-box diagonal.
    scale: f64,
    settings: MapSettings,
    /// Choose among a level's best candidates by laying out everything below
    /// each (small hierarchies only).
    lookahead: bool,
    /// Root size against the prototype's (for `NeighborParams::prototype`).
    prototype_scale: f64,
    monitor: &'a Monitor<'a>,
}

/// What [`descend`] returns: the score of the deepest level, the cells, the
/// report and the sum of per-diagram errors.
type Descent = (f64, Vec<Option<LayoutCell>>, Report, f64);

/// One start of a level's optimisation: its score, the optimised diagrams,
/// the matched-and-swapped diagrams it began from (the repair's fallback)
/// and the recorded frames.
struct Candidate {
    score: f64,
    diagrams: Vec<Diagram>,
    initial: Vec<Diagram>,
    frames: Vec<Frame>,
}

/// Lays out level `depth + 1` and everything below it, given the cells down to
/// `depth`: each start of the level is a [`Candidate`]; the best (or, with
/// lookahead, the best few, each laid out to the bottom) is kept.
fn descend(
    ctx: &Context<'_>,
    depth: usize,
    cells: Vec<Option<LayoutCell>>,
) -> Result<Descent, LayoutError> {
    if depth >= ctx.dataset.max_depth() {
        return Ok((
            leaf_score(ctx, depth, &cells),
            cells,
            Report::default(),
            0.0,
        ));
    }
    let input = LevelInput::new(ctx, depth, &cells);
    if input.links.is_empty() && ctx.method == Method::Neighbor && !ctx.np.prototype {
        return plain_level(ctx, depth, &input.parents, input.polygons, cells);
    }
    let lv = LevelCtx::new(&input.links, ctx.scale, ctx.np);
    let mut candidates = level_candidates(ctx, depth, &input, &lv)?;
    // Best first; the stable sort keeps earlier starts first among equals.
    candidates.sort_by(|a, b| b.score.total_cmp(&a.score));
    let keep = if ctx.lookahead {
        LOOKAHEAD_CANDIDATES
    } else {
        1
    };
    candidates.truncate(keep);
    let mut best: Option<Descent> = None;
    for candidate in candidates {
        let below = descend_from(ctx, depth, candidate, &lv, cells.clone())?;
        if best.as_ref().is_none_or(|b| below.0 > b.0) {
            best = Some(below);
        }
    }
    Ok(best.unwrap_or((0.0, cells, Report::default(), 0.0)))
}

/// What a level's starts share: its parents (nodes at `depth` with
/// children), their cells, its nodes' projected points fitted to the root's
/// box, and its constraints in level-local indices.
struct LevelInput {
    parents: Vec<usize>,
    /// Nodes of the level: the parents' children, in parent order.
    nodes: usize,
    proj_of: Vec<Point>,
    links: LevelLinks,
    polygons: Vec<ConvexPolygon>,
}

impl LevelInput {
    fn new(ctx: &Context<'_>, depth: usize, cells: &[Option<LayoutCell>]) -> Self {
        let dataset = ctx.dataset;
        let n = dataset.len();
        let parents: Vec<usize> = (0..n)
            .filter(|&i| dataset.node(i).depth == depth && !dataset.node(i).children.is_empty())
            .collect();
        let level: Vec<usize> = parents
            .iter()
            .flat_map(|p| dataset.node(*p).children.iter().copied())
            .collect();
        let projected = projection::fit_into(
            &level.iter().map(|i| ctx.projection[*i]).collect::<Vec<_>>(),
            ctx.root_box.0,
            ctx.root_box.1,
        );
        let mut proj_of = vec![Point::ZERO; n];
        for (i, p) in level.iter().zip(projected) {
            proj_of[*i] = p;
        }
        let links = LevelLinks::new(dataset, &level, ctx.constraints, depth + 1);
        let polygons: Vec<ConvexPolygon> = parents
            .iter()
            .map(|&p| {
                cells[p]
                    .as_ref()
                    .map(|c| c.polygon.clone())
                    .expect("invariant: parents are laid out before their children")
            })
            .collect();
        LevelInput {
            parents,
            nodes: level.len(),
            proj_of,
            links,
            polygons,
        }
    }
}

/// Runs every start of level `depth + 1` ([`starts_for`] with our schedule,
/// one otherwise), reporting progress to the monitor, which may stop it.
fn level_candidates(
    ctx: &Context<'_>,
    depth: usize,
    input: &LevelInput,
    lv: &LevelCtx<'_>,
) -> Result<Vec<Candidate>, LayoutError> {
    let dataset = ctx.dataset;
    let starts = if ctx.method == Method::Neighbor && !ctx.np.prototype {
        starts_for(input.nodes, ctx.np)
    } else {
        1
    };
    let diagrams_here = input
        .parents
        .iter()
        .filter(|p| dataset.node(**p).children.len() > 1)
        .count();
    let progress = |tick: usize| Progress {
        level: depth + 1,
        levels: dataset.max_depth(),
        diagram: 0,
        diagrams: diagrams_here,
        tick,
        ticks: ctx.np.ticks,
    };
    if !ctx.monitor.report(progress(0)) {
        return Err(LayoutError::Cancelled);
    }
    let tick_done = |tick: usize| ctx.monitor.report(progress(tick));
    let mut candidates: Vec<Candidate> = Vec::new();
    for start in 0..starts {
        let mut recorder = Recorder::new(depth + 1, ctx.np.frames, ctx.np.ticks);
        let (score, diagrams, initial) = run_level(
            ctx,
            &input.parents,
            &input.polygons,
            &input.proj_of,
            lv,
            depth,
            start,
            recorder.as_mut(),
            &tick_done,
        )?;
        let frames = recorder.map(Recorder::into_frames).unwrap_or_default();
        candidates.push(Candidate {
            score,
            diagrams,
            initial,
            frames,
        });
    }
    Ok(candidates)
}

/// Finishes one candidate of level `depth + 1` (polish, real areas, repairs),
/// writes it into `cells` and lays out everything below.
fn descend_from(
    ctx: &Context<'_>,
    depth: usize,
    candidate: Candidate,
    lv: &LevelCtx<'_>,
    mut cells: Vec<Option<LayoutCell>>,
) -> Result<Descent, LayoutError> {
    let (dataset, np) = (ctx.dataset, ctx.np);
    let Candidate {
        mut diagrams,
        initial,
        frames,
        ..
    } = candidate;
    if ctx.method == Method::Neighbor && !np.prototype {
        swap::exhaustive_polish(&mut diagrams, lv);
    }
    retarget(&mut diagrams, dataset, ctx.params, np);
    let repairs = secure_level(&mut diagrams, &initial, np, ctx.settings, ctx.params.seed);
    if repairs.fallbacks > 0 {
        // A fallback is a start, optimised with the floored areas.
        retarget(&mut diagrams, dataset, ctx.params, np);
    }
    let (mut report, error_sum) = apply_level(diagrams, &mut cells);
    report.repaired = repairs.repaired;
    report.fallbacks = repairs.fallbacks;
    report.frames = frames;
    let (score, cells, below, below_sum) = descend(ctx, depth + 1, cells)?;
    Ok((score, cells, report.merge(below), error_sum + below_sum))
}

/// Lays out level `depth + 1` with the plain engine, each diagram as the
/// plain layout divides it (`treemap::divide`: the same seed, the same cells
/// bit for bit), then everything below. For a level with nothing to preserve
/// ([`LevelLinks::is_empty`]): issue 23's "nothing to preserve, nothing to
/// pay". The method's CVT, matching, swaps, attraction ticks and restarts
/// only serve constraints; without any, a flat list of 100,000 nodes took
/// them for ever, where the plain layout takes seconds.
fn plain_level(
    ctx: &Context<'_>,
    depth: usize,
    parents: &[usize],
    polygons: Vec<ConvexPolygon>,
    mut cells: Vec<Option<LayoutCell>>,
) -> Result<Descent, LayoutError> {
    let dataset = ctx.dataset;
    let diagrams = parents
        .iter()
        .filter(|p| dataset.node(**p).children.len() > 1)
        .count();
    let progress = Progress {
        level: depth + 1,
        levels: dataset.max_depth(),
        diagram: 0,
        diagrams,
        tick: 0,
        ticks: 0,
    };
    if !ctx.monitor.report(progress) {
        return Err(LayoutError::Cancelled);
    }
    let divisions: Vec<Division> = parents
        .par_iter()
        .zip(polygons)
        .map(|(&parent, polygon)| match dataset.node(parent).children.as_slice() {
            [only] => single_child(*only, polygon),
            // After a stop the rest are skipped; the run returns an error.
            _ if ctx.monitor.stopped() => single_child(parent, polygon),
            _ => divide(dataset, ctx.params, ctx.settings, parent, polygon),
        })
        .collect();
    if ctx.monitor.stopped() {
        return Err(LayoutError::Cancelled);
    }
    let mut report = Report::default();
    let mut error_sum = 0.0;
    for d in divisions {
        if d.optimized {
            report.diagrams += 1;
            report.iterations += d.iterations;
            error_sum += d.error;
            report.area_error_max = report.area_error_max.max(d.error);
            if !d.converged {
                report.unconverged += 1;
            }
        }
        report.degenerate += d.degenerate;
        for (child, cell) in d.cells {
            cells[child] = Some(cell);
        }
    }
    let (score, cells, below, below_sum) = descend(ctx, depth + 1, cells)?;
    Ok((score, cells, report.merge(below), error_sum + below_sum))
}

/// The realised constraints of the deepest level (the lookahead's measure).
fn leaf_score(ctx: &Context<'_>, depth: usize, cells: &[Option<LayoutCell>]) -> f64 {
    let dataset = ctx.dataset;
    let leaves: Vec<usize> = (0..dataset.len())
        .filter(|&i| dataset.node(i).depth == depth)
        .collect();
    if !ctx.lookahead || leaves.iter().any(|i| cells[*i].is_none()) {
        return 0.0;
    }
    let links = LevelLinks::new(dataset, &leaves, ctx.constraints, depth);
    let layout = Layout {
        canvas: ctx.params.canvas,
        cells: leaves.iter().filter_map(|i| cells[*i].clone()).collect(),
    };
    let all: Vec<usize> = (0..leaves.len()).collect();
    links.realized(&layout.level_adjacency(&all)) as f64
}

/// Writes a level's diagrams into `cells`; returns its report and error sum.
/// A cell still empty after [`secure_level`] (not seen in practice) gets a
/// sliver, as in the plain layout, counted in [`Report::degenerate`].
fn apply_level(diagrams: Vec<Diagram>, cells: &mut [Option<LayoutCell>]) -> (Report, f64) {
    let mut report = Report::default();
    let mut error_sum = 0.0;
    for d in diagrams {
        match d {
            Diagram::Single { child, polygon } => {
                cells[child] = Some(LayoutCell {
                    site: polygon.centroid(),
                    power_weight: 0.0,
                    polygon,
                });
            }
            Diagram::Sim { children, sim } => {
                let state = sim.state();
                report.count_diagram(
                    state.iteration_count,
                    state.convergence_ratio,
                    sim.converged(),
                );
                error_sum += state.convergence_ratio;
                let clip = sim.clip().clone();
                let (sites, diagram) = sim.into_parts();
                for ((child, site), cell) in children.iter().zip(&sites).zip(diagram.cells) {
                    let polygon = cell.polygon.unwrap_or_else(|| {
                        report.degenerate += 1;
                        sliver(&clip, site.position)
                    });
                    cells[*child] = Some(LayoutCell {
                        site: site.position,
                        power_weight: site.weight,
                        polygon,
                    });
                }
            }
        }
    }
    (report, error_sum)
}

/// Lays out one level from one start: initialise every diagram, swap, aim at
/// the real areas, optimise by `method`. Returns the level's score, its
/// diagrams, and the diagrams as they were when the optimisation began (the
/// fallback of [`secure_level`]).
#[allow(clippy::too_many_arguments)]
fn run_level(
    ctx: &Context<'_>,
    parents: &[usize],
    polygons: &[ConvexPolygon],
    proj_of: &[Point],
    lv: &LevelCtx<'_>,
    depth: usize,
    start: usize,
    mut recorder: Option<&mut Recorder>,
    tick_done: &dyn Fn(usize) -> bool,
) -> Result<(f64, Vec<Diagram>, Vec<Diagram>), LayoutError> {
    let (dataset, method, params, np) = (ctx.dataset, ctx.method, ctx.params, ctx.np);
    tracing::debug!(depth, start, "level run");
    let mut run_params = params.clone();
    run_params.seed = params
        .seed
        .wrapping_add((start as u64).wrapping_mul(0x9e37_79b9));
    let mut diagrams: Vec<Diagram> = parents
        .par_iter()
        .zip(polygons.par_iter())
        .map(|(&parent, polygon)| {
            init_diagram(
                dataset,
                parent,
                polygon.clone(),
                proj_of,
                method,
                &run_params,
                np,
                ctx.settings,
            )
        })
        .collect();
    tracing::debug!("level initialised");
    if matches!(method, Method::MatchSwap | Method::Neighbor) {
        for _ in 0..np.swap_rounds {
            swap::swap_round(&mut diagrams, lv);
        }
        tracing::debug!(rounds = np.swap_rounds, "level start swapped");
    }
    if let Some(r) = recorder.as_deref_mut() {
        let label = match method {
            Method::MatchSwap | Method::Neighbor => "matched and swapped",
            _ => "initial",
        };
        r.take(label, frame_cells(&diagrams));
    }
    // Swaps compared cells of the equal-area CVT; from here on cells aim for
    // their real areas.
    diagrams.par_iter_mut().for_each(|d| {
        if let Diagram::Sim { children, sim } = d {
            if let Some(parent) = children.first().and_then(|c| dataset.node(*c).parent) {
                sim.set_targets(sim_targets(dataset, sim.clip(), parent, params));
            }
        }
    });
    let initial = diagrams.clone();
    let stopped = |_| LayoutError::Cancelled;
    let score = match method {
        Method::Neighbor if !np.prototype => {
            let (score, chosen) = optimize_level(diagrams, lv, recorder.as_deref_mut(), tick_done)
                .map_err(stopped)?;
            diagrams = chosen;
            score.value()
        }
        Method::Neighbor => {
            let limits = Distances::prototype(ctx.prototype_scale, depth + 1);
            optimize_prototype(
                &mut diagrams,
                lv,
                &limits,
                recorder.as_deref_mut(),
                tick_done,
            )
            .map_err(stopped)?;
            0.0
        }
        Method::MatchSwap => {
            diagrams.par_iter_mut().for_each(|d| settle(d, np));
            0.0
        }
        _ => {
            diagrams.par_iter_mut().for_each(|d| {
                if let Diagram::Sim { sim, .. } = d {
                    sim.run();
                }
            });
            0.0
        }
    };
    if let Some(r) = recorder {
        r.take("final", frame_cells(&diagrams));
    }
    Ok((score, diagrams, initial))
}

#[cfg(test)]
mod tests {
    use crate::layout::{compute, Method, Request};
    use nptreemap_formats::{Dataset, DatasetBuilder, NodeSpec, SimilarityHint};

    /// Groups of leaves (ids `g{g}n{i}`) with neighbour lists; `pairs` links
    /// leaves by id.
    fn related(groups: &[usize], pairs: &[(&str, &str)]) -> Dataset {
        let mut b = DatasetBuilder::new();
        b.similarity_hint(SimilarityHint::NeighborList);
        b.add(NodeSpec::new("root"));
        for (g, &n) in groups.iter().enumerate() {
            b.add(NodeSpec::new(format!("g{g}")).parent("root"));
            for i in 0..n {
                let id = format!("g{g}n{i}");
                let mut spec = NodeSpec::new(id.clone())
                    .parent(format!("g{g}"))
                    .weight(1.0 + ((g * 7 + i * 3) % 5) as f64);
                for (a, other) in pairs.iter().filter(|(a, _)| *a == id) {
                    let _ = a;
                    spec = spec.relation(*other);
                }
                b.add(spec);
            }
        }
        b.build().expect("valid")
    }

    fn run(ds: &Dataset, method: Method) -> crate::layout::Computed {
        let request = Request {
            method: Some(method),
            ..Request::default()
        };
        compute(ds, &request).expect("layout")
    }

    /// Issue 23, item 3 (issue 21, item 8): nothing to preserve, nothing to
    /// pay. A flat border list of 100,000 nodes without pairs never finished
    /// under the neighbourhood method; with no constraint at all it is the
    /// plain layout, bit for bit.
    #[test]
    fn no_constraints_is_the_plain_layout() {
        let ds = related(&[30, 20, 10], &[]);
        let neighbor = run(&ds, Method::Neighbor);
        assert!(neighbor.constraints.is_empty());
        assert_eq!(neighbor.layout, run(&ds, Method::Plain).layout);
    }

    /// A level without constraints of its own or below it across its
    /// parents (here the top level: every pair lies inside group 0) is laid
    /// out by the plain engine; the level below still preserves its pairs.
    #[test]
    fn a_level_without_constraints_is_laid_out_plain() {
        let pairs = [
            ("g0n0", "g0n5"),
            ("g0n1", "g0n7"),
            ("g0n2", "g0n9"),
            ("g0n3", "g0n4"),
        ];
        let ds = related(&[12, 8, 6, 5], &pairs);
        let neighbor = run(&ds, Method::Neighbor);
        assert!(!neighbor.constraints.is_empty());
        let plain = run(&ds, Method::Plain);
        for &g in &neighbor.dataset.node(neighbor.dataset.root()).children {
            assert_eq!(
                neighbor.layout.cells[g], plain.layout.cells[g],
                "group {}",
                neighbor.dataset.node(g).id
            );
        }
        assert_ne!(neighbor.layout, plain.layout, "the leaves are arranged");
    }
}
