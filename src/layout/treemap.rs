//! The top-down recursion: the root takes the outline, then every internal node's
//! cell is divided among its children by one `MapSimulation`, level by level.
//! Diagrams of one level are independent, so they run in parallel; each draws
//! its randomness from the run seed and its own node id, so the result does not
//! depend on scheduling.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::map::{MapSettings, MapSimulation};
use super::progress::{Monitor, Progress};
use super::{seed, Canvas, Layout, LayoutCell, LayoutError, Params, Report};
use crate::geom::{ConvexPolygon, Point};
use crate::rng::Rng;
use nptreemap_formats::Dataset;

/// Outcome of dividing one parent's cell.
pub(super) struct Division {
    pub(super) cells: Vec<(usize, LayoutCell)>,
    pub(super) iterations: usize,
    pub(super) error: f64,
    pub(super) converged: bool,
    pub(super) optimized: bool,
    pub(super) degenerate: usize,
}

/// Lays out the whole hierarchy.
///
/// Zero-weight rule: a child's target area uses `max(value, min_weight_ratio ×
/// heaviest sibling's value)`, so zero-weight children get a small visible cell;
/// when every child of a node weighs zero they share its cell equally. A node
/// with one child hands it its own cell unchanged. (With `zero_weights: hide`,
/// the default of [`compute`](super::compute()), no child of weight 0 is left
/// by the time the layout runs: [`zero::apply`](super::zero::apply).)
pub fn layout(dataset: &Dataset, params: &Params) -> Result<(Layout, Report), LayoutError> {
    layout_with(dataset, params, &Monitor::silent())
}

/// [`layout`] reporting to `monitor`, which may stop it.
pub(crate) fn layout_with(
    dataset: &Dataset,
    params: &Params,
    monitor: &Monitor<'_>,
) -> Result<(Layout, Report), LayoutError> {
    let settings = map_settings(params);
    top_down(dataset, params, monitor, |parent, polygon| {
        divide(dataset, params, settings, parent, polygon)
    })
}

/// The stopping rules of every diagram of a run.
pub(super) fn map_settings(params: &Params) -> MapSettings {
    MapSettings {
        convergence_ratio: params.convergence_ratio,
        max_iterations: params.max_iterations,
        min_iterations: params.min_iterations.min(params.max_iterations),
    }
}

/// The top-down pass shared by the cold and the warm layout: the root takes
/// the outline, a node with one child hands it its own cell, and every node
/// with several children has its cell split by `divide(parent, cell)`.
/// Every finished diagram is reported to `monitor`; once it asks to stop, no
/// further diagram starts and the run ends with [`LayoutError::Cancelled`].
pub(super) fn top_down(
    dataset: &Dataset,
    params: &Params,
    monitor: &Monitor<'_>,
    divide: impl Fn(usize, ConvexPolygon) -> Division + Sync,
) -> Result<(Layout, Report), LayoutError> {
    params.validate()?;
    let root_polygon = params.outline.polygon(params.canvas)?;
    let n = dataset.len();
    let mut cells: Vec<Option<LayoutCell>> = vec![None; n];
    let root = dataset.root();
    cells[root] = Some(LayoutCell {
        site: root_polygon.centroid(),
        power_weight: 0.0,
        polygon: root_polygon,
    });

    let mut report = Report::default();
    let mut error_sum = 0.0;
    let mut frontier = vec![root];
    let mut level = 0;
    while !frontier.is_empty() {
        level += 1;
        let diagrams = frontier
            .iter()
            .filter(|p| dataset.node(**p).children.len() > 1)
            .count();
        let done = AtomicUsize::new(0);
        let progress = |diagram: usize| Progress {
            level,
            levels: dataset.max_depth(),
            diagram,
            diagrams,
            tick: 0,
            ticks: 0,
        };
        if !monitor.report(progress(0)) {
            return Err(LayoutError::Cancelled);
        }
        let divisions: Vec<Division> = frontier
            .par_iter()
            .filter(|p| !dataset.node(**p).children.is_empty())
            .map(|&parent| {
                let polygon = cells[parent]
                    .as_ref()
                    .map(|c| c.polygon.clone())
                    .expect("invariant: a level's cells are set before the next level");
                match dataset.node(parent).children.as_slice() {
                    [only] => single_child(*only, polygon),
                    // After a stop the rest are skipped (cheap stand-ins that
                    // are never used: the run returns an error).
                    _ if monitor.stopped() => single_child(parent, polygon),
                    _ => {
                        let division = divide(parent, polygon);
                        let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                        monitor.report(progress(finished));
                        division
                    }
                }
            })
            .collect();
        if monitor.stopped() {
            return Err(LayoutError::Cancelled);
        }
        let mut next = Vec::new();
        for d in divisions {
            if d.optimized {
                report.count_diagram(d.iterations, d.error, d.converged);
                if d.iterations == 0 {
                    report.reused += 1;
                }
                error_sum += d.error;
            }
            report.degenerate += d.degenerate;
            for (child, cell) in d.cells {
                cells[child] = Some(cell);
                next.push(child);
            }
        }
        frontier = next;
    }
    report.set_mean(error_sum);
    Ok((finish(dataset, params.canvas, cells), report))
}

/// An only child takes its parent's cell unchanged.
pub(super) fn single_child(child: usize, polygon: ConvexPolygon) -> Division {
    let cell = LayoutCell {
        site: polygon.centroid(),
        power_weight: 0.0,
        polygon,
    };
    Division {
        cells: vec![(child, cell)],
        iterations: 0,
        error: 0.0,
        converged: true,
        optimized: false,
        degenerate: 0,
    }
}

/// The finished layout from every node's cell (all set by the top-down pass);
/// checked in debug builds (style principle 11).
pub(super) fn finish(dataset: &Dataset, canvas: Canvas, cells: Vec<Option<LayoutCell>>) -> Layout {
    let cells = cells
        .into_iter()
        .map(|c| c.expect("invariant: every node is reached from the root"))
        .collect();
    let layout = Layout { canvas, cells };
    debug_assert_eq!(layout.sanity_check(dataset), Ok(()));
    layout
}

/// Share of a diagram's area target (`convergence_ratio`) that the floor of
/// [`layout`]'s zero-weight rule may use: the rest is left to the optimiser,
/// so that a converged diagram is within the target of its real weights.
const FLOOR_BUDGET_SHARE: f64 = 0.9;

/// The smallest floor, as a share of the heaviest sibling: it keeps every
/// cell positive even with `min_weight_ratio` = 0 (areas below that are
/// invisible at any size).
const MIN_FLOOR: f64 = 1e-9;

/// Steps of the bisection for a floor within budget (2⁻⁶⁰ of the range).
const FLOOR_BISECTIONS: usize = 60;

/// Target areas for the children of a cell of area `area` (see [`layout`] for
/// the zero-weight rule), with the floor lowered where needed so that the floored areas differ from the weights' by at most `budget`
/// (Σ |floored share − weight share|, the checker's diagram area error);
/// also returns that difference, the slack the diagram's optimiser must
/// leave ([`MapSimulation::set_slack`]). Issue 23 item 6: `/usr/bin` (one
/// 127 MB binary beside hundreds of small scripts) had 13.5% of its area
/// moved by a 1:1000 floor while its diagram counted as converged.
pub(super) fn floored_targets(
    values: &[f64],
    area: f64,
    min_weight_ratio: f64,
    budget: f64,
) -> (Vec<f64>, f64) {
    let max = values.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return (vec![area / values.len() as f64; values.len()], 0.0);
    }
    let ratio = min_weight_ratio.max(MIN_FLOOR);
    let floor = max * ratio;
    let relative: Vec<f64> = values.iter().map(|v| v / max).collect();
    let (lo, slack, lowered) = floor_within(&relative, ratio, budget);
    let eff: Vec<f64> = if lowered {
        relative.iter().map(|v| v.max(lo)).collect()
    } else if floor >= f64::MIN_POSITIVE {
        values.iter().map(|v| v.max(floor)).collect()
    } else {
        // A subnormal heaviest weight (5e-324) makes the floor underflow to
        // 0 and a zero sibling's target 0, an empty cell (found by the fuzz
        // run): take the weights relative to the heaviest instead. Normal
        // weights keep the branch above, and their exact rounding.
        relative.iter().map(|v| v.max(ratio)).collect()
    };
    let total: f64 = eff.iter().sum();
    let targets = eff
        .iter()
        .map(|v| {
            let target = area * v / total;
            // Weights near f64's maximum overflow `area * v` (a 1e308 leaf
            // beside a weight of 2 got half the cell); the share first keeps
            // it finite. Not always: the product's rounding is the goldens'.
            if target.is_finite() {
                target
            } else {
                area * (v / total)
            }
        })
        .collect();
    (targets, slack)
}

/// The floor, as a share of the heaviest of the `relative` weights (the
/// heaviest is 1): `ratio` when its error is within `budget`, else the
/// largest floor that is (the error grows with the floor); its error; and
/// whether it was lowered.
fn floor_within(relative: &[f64], ratio: f64, budget: f64) -> (f64, f64, bool) {
    let slack = floor_error(relative, ratio);
    if slack <= budget {
        return (ratio, slack, false);
    }
    let (mut lo, mut hi) = (MIN_FLOOR.min(ratio), ratio);
    for _ in 0..FLOOR_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if floor_error(relative, mid) <= budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, floor_error(relative, lo), true)
}

/// Every node's weight as the picture draws it, for `zero_weights: floor`
/// (issue 34: area errors are measured against what the picture promises):
/// its value, except that a child of weight 0 beside heavier siblings weighs
/// the floor its diagram used ([`floored_targets`], in the siblings' units),
/// and children that all weigh 0 share their parent's drawn weight equally,
/// as they share its cell. Parents come before children in a dataset, so
/// one pass suffices.
pub(crate) fn drawn_weights(dataset: &Dataset, params: &Params) -> Vec<f64> {
    let budget = FLOOR_BUDGET_SHARE * params.convergence_ratio;
    let ratio = params.min_weight_ratio.max(MIN_FLOOR);
    let mut drawn: Vec<f64> = dataset.nodes().iter().map(|n| n.value).collect();
    for (parent, node) in dataset.nodes().iter().enumerate() {
        let kids = &node.children;
        let values: Vec<f64> = kids.iter().map(|&c| dataset.node(c).value).collect();
        let max = values.iter().copied().fold(0.0, f64::max);
        if !values.contains(&0.0) {
            continue;
        }
        let floor = if max <= 0.0 {
            drawn[parent] / kids.len() as f64
        } else {
            let relative: Vec<f64> = values.iter().map(|v| v / max).collect();
            max * floor_within(&relative, ratio, budget).0
        };
        for (&c, v) in kids.iter().zip(&values) {
            if *v == 0.0 {
                drawn[c] = floor;
            }
        }
    }
    drawn
}

/// Σ |share of `max(w, floor)` − share of `w`| over `weights` (relative to
/// the heaviest, so in (0, 1], at least one of them positive).
fn floor_error(weights: &[f64], floor: f64) -> f64 {
    let total: f64 = weights.iter().sum();
    let floored: f64 = weights.iter().map(|w| w.max(floor)).sum();
    weights
        .iter()
        .map(|w| (w.max(floor) / floored - w / total).abs())
        .sum()
}

/// The cold start of one diagram: well-spread sites, equal weights, the full
/// optimisation (Lloyd steps plus weight steps).
pub(super) fn divide(
    dataset: &Dataset,
    params: &Params,
    settings: MapSettings,
    parent: usize,
    polygon: ConvexPolygon,
) -> Division {
    let children = &dataset.node(parent).children;
    let (targets, slack) = child_targets(dataset, parent, &polygon, params);
    let mut rng = Rng::for_key(params.seed, &dataset.node(parent).id);
    let positions = seed::halton_positions(&polygon, children.len(), &mut rng);
    let mut sim = MapSimulation::new(polygon.clone(), targets, positions, None, settings, rng);
    sim.set_slack(slack);
    sim.run();
    division_of(children, sim, &polygon)
}

/// Target areas of `parent`'s children inside `polygon`, and the slack their
/// floor takes from the area target ([`floored_targets`]).
pub(crate) fn child_targets(
    dataset: &Dataset,
    parent: usize,
    polygon: &ConvexPolygon,
    params: &Params,
) -> (Vec<f64>, f64) {
    child_targets_within(
        dataset,
        parent,
        polygon,
        params,
        FLOOR_BUDGET_SHARE * params.convergence_ratio,
    )
}

/// [`child_targets`] with the floor's own `budget` (infinite: the configured
/// floor, whatever it costs the areas).
pub(crate) fn child_targets_within(
    dataset: &Dataset,
    parent: usize,
    polygon: &ConvexPolygon,
    params: &Params,
    budget: f64,
) -> (Vec<f64>, f64) {
    let values: Vec<f64> = dataset
        .node(parent)
        .children
        .iter()
        .map(|c| dataset.node(*c).value)
        .collect();
    floored_targets(&values, polygon.area(), params.min_weight_ratio, budget)
}

/// The cells of a finished simulation, one per child (a sliver stands in for
/// an empty one).
pub(super) fn division_of(
    children: &[usize],
    sim: MapSimulation,
    polygon: &ConvexPolygon,
) -> Division {
    let iterations = sim.state().iteration_count;
    let error = sim.state().convergence_ratio;
    let converged = sim.converged();
    let (sites, diagram) = sim.into_parts();
    let mut degenerate = 0;
    let cells = children
        .iter()
        .zip(sites.iter().zip(diagram.cells))
        .map(|(&child, (site, cell))| {
            let polygon = cell.polygon.unwrap_or_else(|| {
                degenerate += 1;
                sliver(polygon, site.position)
            });
            (
                child,
                LayoutCell {
                    site: site.position,
                    power_weight: site.weight,
                    polygon,
                },
            )
        })
        .collect();
    Division {
        cells,
        iterations,
        error,
        converged,
        optimized: true,
        degenerate,
    }
}

/// Last resort for a cell the optimiser could not keep non-empty (the repair
/// step makes this unreachable in practice; [`Report::degenerate`] counts it): a
/// triangle of a millionth of the parent's size between the site and the
/// parent's centroid, so the node still has a drawable cell inside its parent.
pub(super) fn sliver(parent: &ConvexPolygon, at: Point) -> ConvexPolygon {
    let c = parent.centroid();
    let a = at + (c - at) * 0.5;
    let e = 1e-6 * parent.diameter_bound();
    ConvexPolygon::from_convex(vec![a, a + Point::new(e, 0.0), a + Point::new(0.0, e)])
        .unwrap_or_else(|| parent.clone())
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_subnormal_heaviest_weight_still_floors_its_siblings() {
        let t = super::floored_targets(&[0.0, 5e-324], 1.0, 0.001, f64::INFINITY).0;
        assert!(t.iter().all(|a| *a > 0.0 && a.is_finite()), "{t:?}");
        assert!((t[0] / t[1] - 0.001).abs() < 1e-12, "{t:?}");
        assert!((t.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{t:?}");
    }

    #[test]
    fn the_floor_stays_within_its_budget() {
        // 1,000 leaves of 1 beside one of 10⁶: a 1:1000 floor gives them half
        // the area, where their weights give them a thousandth.
        let mut values = vec![1.0; 1000];
        values.push(1e6);
        let total: f64 = values.iter().sum();
        let (t, slack) = super::floored_targets(&values, 1.0, 0.001, 0.005);
        let err: f64 = t.iter().zip(&values).map(|(a, v)| (a - v / total).abs()).sum();
        assert!(err <= 0.005 + 1e-12 && (err - slack).abs() < 1e-9, "{err} {slack}");
        assert!(t.iter().all(|a| *a > 0.0));
        // Within budget the floor is the configured one, bit for bit.
        let (t, slack) = super::floored_targets(&[0.0, 5.0, 5.0, 0.0, 10.0], 1.0, 0.001, 0.005);
        assert_eq!(t[0], 0.01 / 20.02);
        assert!(slack > 0.0 && slack < 0.005);
    }
}
