//! Similarity-driven layouts, level by level from the root down: the paper's
//! initialisation (a CVT per parent, Kuhn–Munkres matching of projected nodes to
//! CVT sites, greedy swaps; method-reference §4), its two baselines (§6.2), and
//! the joint per-level optimisation of Algorithms 1 and 2 (§5).
//!
//! Where this departs from the prototype, and why:
//! - Cells track their target areas during the whole optimisation (a Newton
//!   weight step every tick, see [`super::map`]) instead of growing in the last
//!   30% of ticks: growth at the end undoes neighbourhoods the attraction has
//!   just built. The final weight-only settling keeps the arrangement.
//! - Distance constants are relative to the level's typical cell size instead of
//!   screen pixels (method-reference §10 row 1), so the method behaves the same
//!   on any canvas and at any depth.
//! - Diagrams of a level read cousins at their start-of-round positions (§5.2),
//!   so they are independent within a round and run in parallel.

use rayon::prelude::*;

use super::frames::{Frame, Recorder};
use super::map::{MapSettings, MapSimulation};
use super::method::Method;
use super::treemap::{finish, target_areas};
use super::{seed, Canvas, Layout, LayoutCell, LayoutError, Params, Report};
use crate::geom::LevelAdjacency;
use crate::geom::{cross, ConvexPolygon, Point};
use crate::neighborhood::{matching, projection, Constraint};
use crate::rng::Rng;
use nptreemap_formats::Dataset;

/// Settings of the similarity-driven methods.
#[derive(Clone, Debug, PartialEq)]
pub struct NeighborParams {
    /// Lloyd ticks of the equal-area CVT every diagram starts from. Default: 40.
    pub cvt_iterations: usize,
    /// Ticks of the joint optimisation per level (the prototype's 150). Default: 150.
    pub ticks: usize,
    /// Greedy swap rounds after matching (method-reference §4.4). Default: 4.
    pub swap_rounds: usize,
    /// One more swap round every this many ticks, until 20 ticks before the end
    /// (the prototype's t = 20, 40, …, 120). 0 disables. Default: 20.
    pub swap_every: usize,
    /// Weight-only ticks at most to settle the areas at the end. Default: 100.
    pub settle_iterations: usize,
    /// Cell-starts per level to spend on independent starts of `neighbor`
    /// (small levels get several, large ones one). Default: 200.
    pub start_budget: usize,
    /// Most independent starts per level. Default: 8.
    pub max_starts: usize,
    /// Hierarchies with at most this many nodes (after preparation) choose
    /// among each level's best candidates by laying out everything below them.
    /// Default: 64.
    pub lookahead_max_nodes: usize,
    /// Run the paper prototype's optimiser instead of ours (method-reference
    /// §5): 151 ticks, weights held at the CVT's until t = 105 and then grown
    /// by d3's ±10% steps, a 0.8 Lloyd step for cells without an attraction
    /// move, pure Lloyd in the last 10 ticks, the prototype's pixel constants
    /// scaled to the canvas, one start. Areas are not settled afterwards, so the
    /// area error is the prototype's too. Default: false.
    pub prototype: bool,
    /// Frames per level recorded while optimising, for the HTML page's
    /// slider (see [`super::frames`]); 0 records none. Recording does not
    /// change the layout. Default: 0.
    pub frames: usize,
}

impl Default for NeighborParams {
    fn default() -> Self {
        Self {
            cvt_iterations: 40,
            ticks: 150,
            swap_rounds: 4,
            swap_every: 20,
            settle_iterations: 100,
            start_budget: 200,
            max_starts: 8,
            lookahead_max_nodes: 64,
            prototype: false,
            frames: 0,
        }
    }
}

/// Distance constants as shares of the level's unit length, the square root of
/// its mean cell area. Derived from the prototype's pixels (method-reference
/// §5.6–5.7) on its country map, where leaf cells average about 4,000 px², a
/// unit of 63 px: `D_OPT` 40 px, `D_MAX` 80 px, step 5 px × 0.8, gap 10 px.
const D_OPT: f64 = 0.63;
const D_MAX: f64 = 1.27;
const STEP: f64 = 0.063;
const GAP: f64 = 0.16;
/// Share of the way to the centroid a Lloyd step goes (the prototype's 0.8, §5.7c).
const CENTROID_STEP: f64 = 0.8;
/// Whether a cell that made no attraction move takes a centroid step, as the
/// prototype's Algorithm 2 does. Off: on the paper's data the Lloyd drift undoes
/// more neighbourhoods than it helps shapes (flare 189 → 240 realised at seed
/// 1, cifar 10 → 13), and the weight step already keeps areas exact.
const CENTROID_STEPS: bool = false;
/// Swap rounds tried on the final settled level (each kept only if it helps).
const POLISH_ROUNDS: usize = 4;
/// Weight of a lifted deeper constraint in a level's score, against 1 for the
/// level's own: the leaf level is what Table 2 counts.
const LIFTED_WEIGHT: usize = 2;
/// Candidates per level followed down the tree when looking ahead.
const LOOKAHEAD_CANDIDATES: usize = 3;
/// Most Lloyd ticks of the final relaxation, and the share of the way to the
/// centroid each goes.
const RELAX_TICKS: usize = 30;
const RELAX_STEP: f64 = 0.5;
/// Levels up to this many cells get the exhaustive swap polish.
const EXHAUSTIVE_MAX_CELLS: usize = 64;
/// Most swap evaluations of the exhaustive polish per level and start.
const EXHAUSTIVE_BUDGET: usize = 400;
/// Ticks between checkpoints (every tick on small hierarchies) at which a settled copy of the level is scored.
const CHECK_EVERY: usize = 10;

/// The distance rules of one level's attraction moves (method-reference
/// §5.6–5.7).
#[derive(Clone, Copy, Debug)]
struct Distances {
    /// Below this, attraction towards a partner stops (`distance_min`).
    d_opt: f64,
    /// Below this, neighbouring cousins slide along the parent edge (`distance_max`).
    d_max: f64,
    /// Length of one attraction move.
    step: f64,
    /// Closest a moved site may come to another site or the parent's boundary.
    gap: f64,
    /// Whether a cell without an attraction move takes a centroid step.
    centroid_steps: bool,
    /// Share of the way to the centroid a centroid step goes.
    centroid_step: f64,
}

/// Area of the prototype's root, a regular 32-gon of circumradius 192 px, the
/// size its pixel constants were tuned for (method-reference §10 row 1).
fn prototype_root_area() -> f64 {
    0.5 * 32.0 * (std::f64::consts::TAU / 32.0).sin() * 192.0 * 192.0
}

impl Distances {
    /// Ours: shares of the level's unit length (see `D_OPT`).
    fn relative(unit: f64) -> Self {
        Self {
            d_opt: D_OPT * unit,
            d_max: D_MAX * unit,
            step: STEP * unit,
            gap: GAP * unit,
            centroid_steps: CENTROID_STEPS,
            centroid_step: CENTROID_STEP,
        }
    }

    /// The prototype's pixels (40, 80, 5 × 0.8, 10 or 15 below depth 2), scaled
    /// by `scale` = the root's size against the prototype's 32-gon of radius 192.
    fn prototype(scale: f64, depth: usize) -> Self {
        Self {
            d_opt: 40.0 * scale,
            d_max: 80.0 * scale,
            step: 4.0 * scale,
            gap: if depth > 2 { 15.0 } else { 10.0 } * scale,
            centroid_steps: true,
            centroid_step: CENTROID_STEP,
        }
    }
}

/// One parent's diagram on the level being laid out.
#[derive(Clone)]
enum Diagram {
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

/// 2-D positions for every node of `dataset`, in any scale: PCA of the
/// feature vectors when every node has one of the same length (after
/// [`crate::neighborhood::prepare`] internal nodes have the mean of their
/// children), else classical MDS of `1 − similarity`.
pub fn projection_of(dataset: &Dataset, similarity: impl Fn(usize, usize) -> f64) -> Vec<Point> {
    let nodes = dataset.nodes();
    let dim = nodes
        .first()
        .and_then(|n| n.features.as_ref().map(Vec::len));
    let uniform = dim.is_some_and(|d| {
        d > 0
            && nodes
                .iter()
                .all(|n| n.features.as_ref().is_some_and(|f| f.len() == d))
    });
    if uniform {
        let vectors: Vec<Vec<f64>> = nodes
            .iter()
            .map(|n| n.features.clone().unwrap_or_default())
            .collect();
        projection::pca_2d(&vectors)
    } else {
        projection::classical_mds_2d(|a, b| 1.0 - similarity(a, b), nodes.len())
    }
}

/// Lays out a prepared dataset (uniform depth) with a similarity-driven method.
/// `constraints` are those of [`crate::neighborhood::build_constraints`];
/// `projection` has one point per node (see [`projection_of`]).
pub fn layout_similar(
    dataset: &Dataset,
    constraints: &[Constraint],
    projection: &[Point],
    method: Method,
    params: &Params,
    np: &NeighborParams,
) -> Result<(Layout, Report), LayoutError> {
    params.validate()?;
    let root_polygon = params.outline.polygon(params.canvas)?;
    let mut cells: Vec<Option<LayoutCell>> = vec![None; dataset.len()];
    cells[dataset.root()] = Some(LayoutCell {
        site: root_polygon.centroid(),
        power_weight: 0.0,
        polygon: root_polygon.clone(),
    });
    let ctx = Context {
        dataset,
        constraints,
        projection,
        method,
        params,
        np,
        root_box: root_polygon.bbox(),
        settings: MapSettings {
            convergence_ratio: params.convergence_ratio,
            max_iterations: params.max_iterations,
            min_iterations: params.min_iterations.min(params.max_iterations),
        },
        lookahead: method == Method::Neighbor
            && !np.prototype
            && dataset.len() <= np.lookahead_max_nodes,
        prototype_scale: (root_polygon.area() / prototype_root_area()).sqrt(),
    };
    let (_, cells, mut report, error_sum) = descend(&ctx, 0, cells);
    if report.diagrams > 0 {
        report.area_error_mean = error_sum / report.diagrams as f64;
    }
    if report.degenerate > 0 {
        return Err(LayoutError::Degenerate {
            cells: report.degenerate,
        });
    }
    Ok((finish(dataset, params.canvas, cells), report))
}

/// How thoroughly a level is searched: small hierarchies (those that also get
/// lookahead) are scored every tick and relaxed at the end; on larger ones both
/// cost more time than they return (Flare: 80 ms for no change).
#[derive(Clone, Copy, Debug)]
struct LevelPlan {
    check_every: usize,
    relax_ticks: usize,
}

impl LevelPlan {
    fn new(small: bool) -> Self {
        if small {
            Self {
                check_every: 1,
                relax_ticks: RELAX_TICKS,
            }
        } else {
            Self {
                check_every: CHECK_EVERY,
                relax_ticks: 0,
            }
        }
    }
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
    settings: MapSettings,
    /// Choose among a level's best candidates by laying out everything below
    /// each (small hierarchies only).
    lookahead: bool,
    /// Root size against the prototype's (for `NeighborParams::prototype`).
    prototype_scale: f64,
}

/// Lays out level `depth + 1` and everything below it, given the cells down to
/// `depth`. Returns the score of the deepest level (realised constraints), the
/// cells, the report and the sum of per-diagram errors.
fn descend(
    ctx: &Context<'_>,
    depth: usize,
    cells: Vec<Option<LayoutCell>>,
) -> (usize, Vec<Option<LayoutCell>>, Report, f64) {
    let dataset = ctx.dataset;
    if depth >= dataset.max_depth() {
        let leaves: Vec<usize> = (0..dataset.len())
            .filter(|&i| dataset.node(i).depth == depth)
            .collect();
        let links = LevelLinks::new(dataset, &leaves, ctx.constraints, depth);
        let layout_cells: Vec<LayoutCell> =
            leaves.iter().filter_map(|i| cells[*i].clone()).collect();
        let score = if layout_cells.len() == leaves.len() {
            let layout = Layout {
                canvas: ctx.params.canvas,
                cells: layout_cells,
            };
            let all: Vec<usize> = (0..leaves.len()).collect();
            links.score_of(&layout.level_adjacency(&all))
        } else {
            0
        };
        return (score, cells, Report::default(), 0.0);
    }
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
    let starts = if ctx.method == Method::Neighbor && !ctx.np.prototype {
        starts_for(level.len(), ctx.np)
    } else {
        1
    };
    let mut candidates: Vec<(usize, Vec<Diagram>, Vec<Frame>)> = (0..starts)
        .map(|start| {
            // Small hierarchies are cheap to score, and a level's best moment
            // is often brief.
            let plan = LevelPlan::new(ctx.lookahead);
            let prototype = ctx
                .np
                .prototype
                .then(|| Distances::prototype(ctx.prototype_scale, depth + 1));
            let mut recorder = Recorder::new(depth + 1, ctx.np.frames, ctx.np.ticks);
            let (score, diagrams) = run_level(
                dataset,
                &parents,
                &polygons,
                &proj_of,
                &links,
                ctx.method,
                ctx.params,
                ctx.np,
                ctx.settings,
                start,
                plan,
                prototype,
                recorder.as_mut(),
            );
            let frames = recorder.map(Recorder::into_frames).unwrap_or_default();
            (score, diagrams, frames)
        })
        .collect();
    // Best first; the stable sort keeps earlier starts first among equals.
    candidates.sort_by_key(|c| std::cmp::Reverse(c.0));
    let keep = if ctx.lookahead {
        LOOKAHEAD_CANDIDATES
    } else {
        1
    };
    candidates.truncate(keep);
    let mut best: Option<(usize, Vec<Option<LayoutCell>>, Report, f64)> = None;
    for (_, diagrams, frames) in candidates {
        let mut cells = cells.clone();
        let (mut report, error_sum) = apply_level(diagrams, &mut cells);
        report.frames = frames;
        let (score, cells, below, below_sum) = descend(ctx, depth + 1, cells);
        if best.as_ref().is_none_or(|b| score > b.0) {
            best = Some((
                score,
                cells,
                add_reports(report, below),
                error_sum + below_sum,
            ));
        }
    }
    best.unwrap_or((0, cells, Report::default(), 0.0))
}

/// Writes a level's diagrams into `cells`; returns its report and error sum.
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
                report.diagrams += 1;
                report.iterations += state.iteration_count;
                error_sum += state.convergence_ratio;
                report.area_error_max = report.area_error_max.max(state.convergence_ratio);
                if !sim.converged() {
                    report.unconverged += 1;
                }
                let (sites, diagram) = sim.into_parts();
                for ((child, site), cell) in children.iter().zip(&sites).zip(diagram.cells) {
                    match cell.polygon {
                        Some(polygon) => {
                            cells[*child] = Some(LayoutCell {
                                site: site.position,
                                power_weight: site.weight,
                                polygon,
                            });
                        }
                        None => report.degenerate += 1,
                    }
                }
            }
        }
    }
    (report, error_sum)
}

fn add_reports(a: Report, b: Report) -> Report {
    Report {
        diagrams: a.diagrams + b.diagrams,
        iterations: a.iterations + b.iterations,
        area_error_mean: 0.0,
        area_error_max: a.area_error_max.max(b.area_error_max),
        unconverged: a.unconverged + b.unconverged,
        reused: a.reused + b.reused,
        degenerate: a.degenerate + b.degenerate,
        frames: a.frames.into_iter().chain(b.frames).collect(),
    }
}

/// Independent starts per level for `neighbor`: a level is cheap when small,
/// and its best start is kept (the level's score decides). Enough starts to
/// spend about `start_budget` cell-starts, between 1 and `max_starts`.
fn starts_for(level_size: usize, np: &NeighborParams) -> usize {
    (np.start_budget / level_size.max(1)).clamp(1, np.max_starts.max(1))
}

/// Lays out one level from one start: initialise every diagram, swap, aim at
/// the real areas, optimise by `method`. Returns the level's score and diagrams.
#[allow(clippy::too_many_arguments)]
fn run_level(
    dataset: &Dataset,
    parents: &[usize],
    polygons: &[ConvexPolygon],
    proj_of: &[Point],
    links: &LevelLinks,
    method: Method,
    params: &Params,
    np: &NeighborParams,
    settings: MapSettings,
    start: usize,
    plan: LevelPlan,
    prototype: Option<Distances>,
    mut recorder: Option<&mut Recorder>,
) -> (usize, Vec<Diagram>) {
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
                settings,
            )
        })
        .collect();
    let canvas = params.canvas;
    if matches!(method, Method::MatchSwap | Method::Neighbor) {
        for _ in 0..np.swap_rounds {
            swap_round(&mut diagrams, links, canvas);
        }
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
            let targets = sim_targets(dataset, sim.clip(), children, params);
            sim.set_targets(targets);
        }
    });
    match method {
        Method::Neighbor => match prototype {
            Some(limits) => optimize_prototype(
                &mut diagrams,
                links,
                canvas,
                np,
                &limits,
                recorder.as_deref_mut(),
            ),
            None => {
                let (score, diagrams) = optimize_level(
                    &mut diagrams,
                    links,
                    canvas,
                    np,
                    plan,
                    recorder.as_deref_mut(),
                );
                if let Some(r) = recorder {
                    r.take("final", frame_cells(&diagrams));
                }
                return (score, diagrams);
            }
        },
        Method::MatchSwap => diagrams.par_iter_mut().for_each(|d| settle(d, np)),
        _ => diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { sim, .. } = d {
                sim.run();
            }
        }),
    }
    if let Some(r) = recorder {
        r.take("final", frame_cells(&diagrams));
    }
    (0, diagrams)
}

/// The level's current cells, for a [`Frame`].
fn frame_cells(diagrams: &[Diagram]) -> Vec<(usize, ConvexPolygon)> {
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

fn sim_targets(
    dataset: &Dataset,
    clip: &ConvexPolygon,
    children: &[usize],
    params: &Params,
) -> Vec<f64> {
    let values: Vec<f64> = children.iter().map(|c| dataset.node(*c).value).collect();
    target_areas(&values, clip.area(), params.min_weight_ratio)
}

/// Builds one parent's diagram in its starting state for `method`.
#[allow(clippy::too_many_arguments)]
fn init_diagram(
    dataset: &Dataset,
    parent: usize,
    polygon: ConvexPolygon,
    projected: &[Point],
    method: Method,
    params: &Params,
    np: &NeighborParams,
    settings: MapSettings,
) -> Diagram {
    let children = dataset.node(parent).children.clone();
    if children.len() == 1 {
        return Diagram::Single {
            child: children[0],
            polygon,
        };
    }
    let k = children.len();
    let mut rng = Rng::for_key(params.seed, &dataset.node(parent).id);
    let targets = sim_targets(dataset, &polygon, &children, params);
    let (positions, weights) = if method == Method::ProjScale {
        let points: Vec<Point> = children.iter().map(|c| projected[*c]).collect();
        (project_and_scale(&polygon, &points, &mut rng), None)
    } else {
        // Equal-area CVT (method-reference §4.2).
        let equal = vec![polygon.area() / k as f64; k];
        let start = seed::halton_positions(&polygon, k, &mut rng);
        let cvt_settings = MapSettings {
            convergence_ratio: 0.0,
            max_iterations: np.cvt_iterations.max(1),
            min_iterations: np.cvt_iterations.max(1),
        };
        let mut cvt = MapSimulation::new(
            polygon.clone(),
            equal,
            start,
            None,
            cvt_settings,
            rng.clone(),
        );
        cvt.run();
        let sites = cvt.state().sites.to_vec();
        let site_pos: Vec<Point> = sites.iter().map(|s| s.position).collect();
        // order[c] = the CVT site child c takes.
        let order: Vec<usize> = if method == Method::RandomCvt {
            let mut perm: Vec<usize> = (0..k).collect();
            for i in (1..k).rev() {
                let j = (rng.next_u64() % (i as u64 + 1)) as usize;
                perm.swap(i, j);
            }
            perm
        } else {
            let points: Vec<Point> = children.iter().map(|c| projected[*c]).collect();
            matching::match_points(&site_pos, &points)
        };
        let positions = order.iter().map(|&s| site_pos[s]).collect();
        let weights = order.iter().map(|&s| sites[s].weight).collect();
        (positions, Some(weights))
    };
    // Similarity methods start from the CVT's equal areas; targets are set when
    // their optimisation starts, so swaps compare cells of the CVT geometry.
    let start_targets = if method == Method::ProjScale {
        targets
    } else {
        vec![polygon.area() / k as f64; k]
    };
    let sim = MapSimulation::new(polygon, start_targets, positions, weights, settings, rng);
    Diagram::Sim {
        children,
        sim: Box::new(sim),
    }
}

/// The projection-and-scale start of Nocaj and Brandes (method-reference §6.2):
/// move the points' hull centroid onto the parent's centroid, then shrink
/// towards it by factors 0.99, 0.89, …, 0.09 until every point is inside.
fn project_and_scale(parent: &ConvexPolygon, points: &[Point], rng: &mut Rng) -> Vec<Point> {
    let c = parent.centroid();
    let hull_center = match ConvexPolygon::new(points.to_vec()) {
        Ok(h) => h.centroid(),
        Err(_) => points.iter().copied().sum::<Point>() / points.len().max(1) as f64,
    };
    let moved: Vec<Point> = points.iter().map(|p| *p - hull_center + c).collect();
    let mut placed = None;
    for step in 0..10 {
        let f = 0.99 - 0.1 * step as f64;
        let scaled: Vec<Point> = moved.iter().map(|p| c + (*p - c) * f).collect();
        if scaled.iter().all(|p| parent.contains(*p)) {
            placed = Some(scaled);
            break;
        }
    }
    let mut out = placed.unwrap_or_else(|| moved.iter().map(|p| c + (*p - c) * 0.09).collect());
    // Points still outside, or on top of each other, start at a random spot.
    for i in 0..out.len() {
        let clash = (0..i).any(|j| out[j] == out[i]);
        if clash || !parent.contains(out[i]) {
            out[i] = parent.sample(rng.next_f64(), rng.next_f64());
        }
    }
    out
}

/// Settles a diagram's areas with its sites held in place.
fn settle(d: &mut Diagram, np: &NeighborParams) {
    if let Diagram::Sim { sim, .. } = d {
        let target = sim.settings().convergence_ratio;
        for _ in 0..np.settle_iterations {
            if sim.settle_weights() <= target {
                break;
            }
        }
    }
}

/// The constraints of one level, in level-local indices.
struct LevelLinks {
    /// Level-local index of every node, `usize::MAX` off the level.
    local: Vec<usize>,
    /// Node index of every level-local index.
    nodes: Vec<usize>,
    /// Partners and scores per level-local index, Stage E order (§3.7): all
    /// score-100 links first, then by score descending; ties by index.
    links: Vec<Vec<(usize, u8)>>,
    /// Constraints of deeper levels lifted to this level: per level-local index,
    /// the partners whose subtrees hold constrained pairs with its subtree, and
    /// how many. A deeper pair can only become neighbours across parents whose
    /// cells touch, so these count towards a level's score.
    lifted: Vec<Vec<(usize, usize)>>,
}

impl LevelLinks {
    fn new(dataset: &Dataset, level: &[usize], constraints: &[Constraint], depth: usize) -> Self {
        let mut local = vec![usize::MAX; dataset.len()];
        for (k, &i) in level.iter().enumerate() {
            local[i] = k;
        }
        let mut links = vec![Vec::new(); level.len()];
        for c in constraints {
            if dataset.node(c.a).depth != depth || c.score <= 1 {
                continue;
            }
            let (a, b) = (local[c.a], local[c.b]);
            if a == usize::MAX || b == usize::MAX {
                continue;
            }
            links[a].push((b, c.score));
            links[b].push((a, c.score));
        }
        for l in &mut links {
            l.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
        }
        let ancestor = |mut i: usize| {
            while dataset.node(i).depth > depth {
                match dataset.node(i).parent {
                    Some(p) => i = p,
                    None => break,
                }
            }
            local[i]
        };
        let mut counts = std::collections::BTreeMap::new();
        for c in constraints {
            if dataset.node(c.a).depth <= depth {
                continue;
            }
            let (a, b) = (ancestor(c.a), ancestor(c.b));
            if a != b && a != usize::MAX && b != usize::MAX {
                *counts.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
            }
        }
        let mut lifted = vec![Vec::new(); level.len()];
        for ((a, b), n) in counts {
            lifted[a].push((b, n));
            lifted[b].push((a, n));
        }
        Self {
            local,
            nodes: level.to_vec(),
            links,
            lifted,
        }
    }

    /// The level's score for an adjacency: realised constraints of the level
    /// plus lifted deeper constraints across touching cells.
    fn score_of(&self, adjacency: &LevelAdjacency) -> usize {
        (0..self.nodes.len())
            .map(|a| {
                let own = self.links[a]
                    .iter()
                    .filter(|(b, _)| *b > a && adjacency.are_adjacent(a, *b))
                    .count();
                let deep: usize = self.lifted[a]
                    .iter()
                    .filter(|(b, _)| *b > a && adjacency.are_adjacent(a, *b))
                    .map(|(_, n)| n)
                    .sum();
                own + LIFTED_WEIGHT * deep
            })
            .sum()
    }

    fn score(&self, a: usize, b: usize) -> Option<u8> {
        self.links[a].iter().find(|(t, _)| *t == b).map(|(_, s)| *s)
    }
}

/// Current geometry of the level: per level-local index the site, centroid,
/// polygon, the diagram it belongs to and its index there.
struct Snapshot {
    site: Vec<Point>,
    centroid: Vec<Point>,
    diagram: Vec<usize>,
    slot: Vec<usize>,
    adjacency: LevelAdjacency,
}

fn snapshot(diagrams: &[Diagram], links: &LevelLinks, canvas: Canvas) -> Snapshot {
    let m = links.nodes.len();
    let mut site = vec![Point::ZERO; m];
    let mut centroid = vec![Point::ZERO; m];
    let mut diagram = vec![0; m];
    let mut slot = vec![0; m];
    let mut polygons: Vec<Option<ConvexPolygon>> = vec![None; m];
    for (d, dg) in diagrams.iter().enumerate() {
        match dg {
            Diagram::Single { child, polygon } => {
                let k = links.local[*child];
                site[k] = polygon.centroid();
                centroid[k] = site[k];
                diagram[k] = d;
                polygons[k] = Some(polygon.clone());
            }
            Diagram::Sim { children, sim } => {
                let state = sim.state();
                for (j, c) in children.iter().enumerate() {
                    let k = links.local[*c];
                    site[k] = state.sites[j].position;
                    centroid[k] = state.diagram.cells[j].centroid;
                    diagram[k] = d;
                    slot[k] = j;
                    polygons[k] = state.diagram.cells[j].polygon.clone();
                }
            }
        }
    }
    // An empty cell (only transiently possible) is given a point-sized stand-in
    // so indices stay aligned; it has no neighbours.
    let cells = polygons
        .into_iter()
        .zip(&site)
        .map(|(p, s)| LayoutCell {
            site: *s,
            power_weight: 0.0,
            polygon: p.unwrap_or_else(|| tiny_square(*s)),
        })
        .collect();
    let layout = Layout { canvas, cells };
    let all: Vec<usize> = (0..m).collect();
    let adjacency = layout.level_adjacency(&all);
    Snapshot {
        site,
        centroid,
        diagram,
        slot,
        adjacency,
    }
}

fn tiny_square(at: Point) -> ConvexPolygon {
    let e = 1e-9;
    ConvexPolygon::from_convex(vec![
        at,
        at + Point::new(e, 0.0),
        at + Point::new(e, e),
        at + Point::new(0.0, e),
    ])
    .unwrap_or_else(|| {
        ConvexPolygon::rectangle(at.x, at.y, 1.0, 1.0).expect("a unit square is a polygon")
    })
}

/// One greedy swap round over the level (method-reference §4.4): candidate
/// pairs of same-parent cells whose exchange realises more constraints, best
/// gain first, each cell swapped at most once and its neighbours left alone.
fn swap_round(diagrams: &mut [Diagram], links: &LevelLinks, canvas: Canvas) -> usize {
    let snap = snapshot(diagrams, links, canvas);
    let adj = &snap.adjacency;
    let realized = |x: usize, at: usize| -> i64 {
        // Partners of x (own and lifted) adjacent to the cell at `at`.
        let own = links.links[x]
            .iter()
            .filter(|(t, _)| *t != at && adj.are_adjacent(*t, at))
            .count();
        let deep: usize = links.lifted[x]
            .iter()
            .filter(|(t, _)| *t != at && adj.are_adjacent(*t, at))
            .map(|(_, n)| n)
            .sum();
        (own + LIFTED_WEIGHT * deep) as i64
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
            if gain > 0 {
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

/// The joint optimisation of one level (paper Algorithm 1): every tick, the
/// level's neighbourhoods are recomputed and every diagram makes one step in
/// which each cell either makes one attraction move (Algorithm 2) or a
/// centroid step, followed by a weight step towards the target areas.
fn optimize_level(
    diagrams: &mut [Diagram],
    links: &LevelLinks,
    canvas: Canvas,
    np: &NeighborParams,
    plan: LevelPlan,
    mut recorder: Option<&mut Recorder>,
) -> (usize, Vec<Diagram>) {
    // The unit length of the level: square root of its mean cell area.
    let total: f64 = diagrams
        .iter()
        .map(|d| match d {
            Diagram::Single { polygon, .. } => polygon.area(),
            Diagram::Sim { sim, .. } => sim.clip().area(),
        })
        .sum();
    let unit = (total / links.nodes.len().max(1) as f64).sqrt();
    // Keep the best state seen: a settled copy is scored at every checkpoint,
    // the matched-and-swapped start included, so the optimisation can only add
    // to what initialisation achieved.
    let mut best = scored_copy(diagrams, links, canvas, np);
    for tick in 0..np.ticks {
        if np.swap_every > 0 && tick > 0 && tick % np.swap_every == 0 && tick + 20 < np.ticks {
            swap_round(diagrams, links, canvas);
        }
        let snap = snapshot(diagrams, links, canvas);
        diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { children, sim } = d {
                let positions = attraction_moves(
                    children,
                    sim,
                    links,
                    &snap,
                    &Distances::relative(unit),
                    true,
                );
                sim.tick_with_positions(&positions);
            }
        });
        if let Some(r) = recorder.as_deref_mut().filter(|r| r.wants(tick)) {
            r.take(format!("tick {}", tick + 1), frame_cells(diagrams));
        }
        if (tick + 1) % plan.check_every == 0 || tick + 1 == np.ticks {
            let candidate = scored_copy(diagrams, links, canvas, np);
            // Ties go to the later state, which has had more optimisation.
            if candidate.0 >= best.0 {
                best = candidate;
            }
        }
    }
    // Polish: swap rounds on the settled geometry with the real areas, kept
    // only while they realise more.
    for _ in 0..POLISH_ROUNDS {
        let mut trial = best.1.clone();
        if swap_round(&mut trial, links, canvas) == 0 {
            break;
        }
        let candidate = scored_copy(&trial, links, canvas, np);
        if candidate.0 <= best.0 {
            break;
        }
        best = candidate;
    }
    let best = exhaustive_polish(best, links, canvas, np);
    relax(best, links, canvas, np, plan.relax_ticks)
}

/// Rounds the cells: damped Lloyd ticks on the chosen state, each kept only
/// while the level's score does not drop. The attraction phase moves sites
/// off their centroids (long cells); this takes back what the arrangement
/// does not need.
fn relax(
    mut best: (usize, Vec<Diagram>),
    links: &LevelLinks,
    canvas: Canvas,
    np: &NeighborParams,
    ticks: usize,
) -> (usize, Vec<Diagram>) {
    for _ in 0..ticks {
        let mut trial = best.1.clone();
        trial.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { sim, .. } = d {
                let state = sim.state();
                let positions: Vec<Point> = state
                    .sites
                    .iter()
                    .zip(&state.diagram.cells)
                    .map(|(s, c)| {
                        let p = s.position + (c.centroid - s.position) * RELAX_STEP;
                        if c.polygon.is_some() && sim.clip().contains(p) {
                            p
                        } else {
                            s.position
                        }
                    })
                    .collect();
                sim.tick_with_positions(&positions);
            }
        });
        let candidate = scored_copy(&trial, links, canvas, np);
        if candidate.0 < best.0 {
            break;
        }
        best = candidate;
    }
    best
}

/// On small levels, try every same-parent swap on the settled geometry, scored
/// exactly, keeping each that raises the level's score (first improvement),
/// within an evaluation budget. The greedy rounds estimate gains from the old
/// adjacency; this measures them.
fn exhaustive_polish(
    mut best: (usize, Vec<Diagram>),
    links: &LevelLinks,
    canvas: Canvas,
    np: &NeighborParams,
) -> (usize, Vec<Diagram>) {
    if links.nodes.len() > EXHAUSTIVE_MAX_CELLS {
        return best;
    }
    let mut evaluations = 0;
    let mut improved = true;
    while improved && evaluations < EXHAUSTIVE_BUDGET {
        improved = false;
        'search: for d in 0..best.1.len() {
            let k = match &best.1[d] {
                Diagram::Sim { children, .. } => children.len(),
                Diagram::Single { .. } => continue,
            };
            for a in 0..k {
                for b in a + 1..k {
                    let mut trial = best.1.clone();
                    if let Diagram::Sim { sim, .. } = &mut trial[d] {
                        sim.swap_sites(&[(a, b)]);
                    }
                    evaluations += 1;
                    let candidate = scored_copy(&trial, links, canvas, np);
                    if candidate.0 > best.0 {
                        best = candidate;
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
    best
}

/// The prototype's optimisation of one level (method-reference §5.2–5.10),
/// for `NeighborParams::prototype`: ticks 0 to `np.ticks` inclusive; weights
/// reset to the CVT's equal level (area/2n, d3's `half-average-area`) until
/// 45 ticks before the end, then grown by d3's clamped multiplicative step;
/// swap rounds at t = 20, 40, … up to 20 ticks before the end; no attraction
/// at t = 0 and in the last 10 ticks (pure 0.8 Lloyd there).
fn optimize_prototype(
    diagrams: &mut [Diagram],
    links: &LevelLinks,
    canvas: Canvas,
    np: &NeighborParams,
    limits: &Distances,
    mut recorder: Option<&mut Recorder>,
) {
    let last = np.ticks;
    let growth_from = last.saturating_sub(45);
    for tick in 0..=last {
        if np.swap_every > 0 && tick > 10 && tick % np.swap_every == 0 && tick + 20 < last {
            swap_round(diagrams, links, canvas);
        }
        let snap = snapshot(diagrams, links, canvas);
        let attract = tick >= 1 && tick + 10 <= last;
        diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { children, sim } = d {
                let positions = attraction_moves(children, sim, links, &snap, limits, attract);
                let reset =
                    (tick < growth_from).then(|| sim.clip().area() / (2.0 * children.len() as f64));
                sim.tick_prototype(&positions, reset);
            }
        });
        if let Some(r) = recorder.as_deref_mut().filter(|r| r.wants(tick)) {
            r.take(format!("tick {}", tick + 1), frame_cells(diagrams));
        }
    }
}

/// A copy of the level with its areas settled, and the number of the level's
/// constraints it realises.
fn scored_copy(
    diagrams: &[Diagram],
    links: &LevelLinks,
    canvas: Canvas,
    np: &NeighborParams,
) -> (usize, Vec<Diagram>) {
    let mut copy = diagrams.to_vec();
    copy.par_iter_mut().for_each(|d| settle(d, np));
    let snap = snapshot(&copy, links, canvas);
    (links.score_of(&snap.adjacency), copy)
}

/// New site positions for one diagram: Algorithm 2 for each cell, furthest
/// strongest link first (§5.4), at most one successful move per cell (§5.6).
fn attraction_moves(
    children: &[usize],
    sim: &MapSimulation,
    links: &LevelLinks,
    snap: &Snapshot,
    limits: &Distances,
    attract: bool,
) -> Vec<Point> {
    let state = sim.state();
    let clip = sim.clip();
    let mut pos: Vec<Point> = state.sites.iter().map(|s| s.position).collect();
    let local: Vec<usize> = children.iter().map(|c| links.local[*c]).collect();
    let (gap, step, d_opt) = (limits.gap, limits.step, limits.d_opt);
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
        let centroid = state.diagram.cells[j].centroid;
        let neighbors_here: Vec<usize> = state.diagram.cells[j]
            .neighbors
            .iter()
            .map(|nb| nb.site)
            .collect();
        let accept = |p: Point, pos: &[Point], cross_parent: bool| -> bool {
            clip.contains(p)
                && neighbors_here.iter().all(|&o| p.distance(pos[o]) >= gap)
                && (!cross_parent || boundary_distance(clip, p) >= gap)
        };
        let mut moved = false;
        if attract && !links.links[me].is_empty() {
            // Different parent first, then same parent; each by distance, furthest first (§5.5).
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
                        if accept(p, &pos, false) {
                            pos[j] = p;
                            moved = true;
                            break;
                        }
                    }
                    continue;
                }
                let (d, edge) = exit_through(clip, centroid, snap.centroid[t]);
                let toward = step_towards(pos[j], snap.site[t], step);
                let slide = edge
                    .and_then(|(a, b)| slide_along(pos[j], centroid, snap.centroid[t], a, b, step));
                if neighbor {
                    let candidate = if d <= limits.d_max { slide } else { toward };
                    if let Some(p) = candidate {
                        if accept(p, &pos, true) {
                            pos[j] = p;
                            moved = true;
                            break;
                        }
                    }
                } else if d > d_opt {
                    if let Some(p) = toward {
                        if accept(p, &pos, true) {
                            pos[j] = p;
                            moved = true;
                            break;
                        }
                    }
                } else if let Some(p) = slide {
                    // Aligning along the parent edge is not a move of its own (§5.6 rule 8).
                    if accept(p, &pos, true) {
                        pos[j] = p;
                    }
                }
            }
        }
        if !moved && limits.centroid_steps {
            let p = pos[j] + (centroid - pos[j]) * limits.centroid_step;
            if clip.contains(p) && state.diagram.cells[j].polygon.is_some() {
                pos[j] = p;
            }
        }
    }
    pos
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

fn step_towards(from: Point, to: Point, step: f64) -> Option<Point> {
    let d = to - from;
    let len = d.length();
    (len > 0.0).then(|| from + d * (step.min(len) / len))
}

/// Where the segment from `from` (inside `clip`) to `to` leaves `clip`: the
/// distance to the exit point and the edge crossed. When `to` is inside too,
/// the distance to `to` and no edge.
fn exit_through(clip: &ConvexPolygon, from: Point, to: Point) -> (f64, Option<(Point, Point)>) {
    let pts = clip.points();
    let dir = to - from;
    let mut best: Option<(f64, (Point, Point))> = None;
    for k in 0..pts.len() {
        let a = pts[k];
        let b = pts[(k + 1) % pts.len()];
        let e = b - a;
        let denom = cross(dir, e);
        if denom == 0.0 {
            continue;
        }
        let t = cross(a - from, e) / denom;
        let u = cross(a - from, dir) / denom;
        if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, (a, b)));
        }
    }
    match best {
        Some((t, edge)) => (dir.length() * t, Some(edge)),
        None => (dir.length(), None),
    }
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

/// Distance from a point inside a convex polygon to its boundary.
fn boundary_distance(clip: &ConvexPolygon, p: Point) -> f64 {
    let pts = clip.points();
    (0..pts.len())
        .map(|k| {
            let a = pts[k];
            let e = pts[(k + 1) % pts.len()] - a;
            cross(e, p - a) / e.length().max(f64::MIN_POSITIVE)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> ConvexPolygon {
        ConvexPolygon::rectangle(0.0, 0.0, 10.0, 10.0).expect("square")
    }

    #[test]
    fn exit_through_finds_the_crossed_edge() {
        let (d, edge) = exit_through(&square(), Point::new(5.0, 5.0), Point::new(15.0, 5.0));
        assert!((d - 5.0).abs() < 1e-12);
        let (a, b) = edge.expect("crosses the right edge");
        assert_eq!((a.x, b.x), (10.0, 10.0));
        // A target inside: its distance and no edge.
        let (d, edge) = exit_through(&square(), Point::new(5.0, 5.0), Point::new(7.0, 5.0));
        assert!((d - 2.0).abs() < 1e-12 && edge.is_none());
    }

    #[test]
    fn slide_aligns_projections_and_stops_when_aligned() {
        let (a, b) = (Point::new(10.0, 0.0), Point::new(10.0, 10.0));
        let p = Point::new(8.0, 2.0);
        let moved = slide_along(p, p, Point::new(12.0, 8.0), a, b, 0.5).expect("not aligned");
        assert_eq!(moved, Point::new(8.0, 2.5));
        assert!(slide_along(p, p, Point::new(12.0, 2.2), a, b, 0.5).is_none());
    }

    #[test]
    fn boundary_distance_inside_a_square() {
        assert!((boundary_distance(&square(), Point::new(2.0, 5.0)) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn project_and_scale_puts_every_point_inside() {
        let parent = ConvexPolygon::regular(Point::new(50.0, 50.0), 10.0, 6).expect("hexagon");
        let points: Vec<Point> = (0..12)
            .map(|k| Point::new((k as f64 * 37.0) % 100.0, (k as f64 * 53.0) % 90.0))
            .collect();
        let out = project_and_scale(&parent, &points, &mut Rng::new(1));
        assert_eq!(out.len(), points.len());
        assert!(out.iter().all(|p| parent.contains(*p)));
    }

    #[test]
    fn small_levels_get_more_starts() {
        let np = NeighborParams::default();
        assert_eq!(starts_for(10_000, &np), 1);
        assert_eq!(starts_for(10, &np), np.max_starts);
        assert!(starts_for(50, &np) >= 1 && starts_for(50, &np) <= np.max_starts);
    }
}
