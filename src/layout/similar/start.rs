//! How every diagram of a level starts (method-reference §4 and §6.2): an
//! equal-area CVT per parent, children assigned to its cells by Kuhn–Munkres on
//! their projections (`match-swap`, `neighbor`) or at random (`random-cvt`),
//! or the projection-and-scale start (`proj-scale`); and how many independent
//! starts a level gets.

use super::level::Diagram;
use super::NeighborParams;
use crate::geom::{ConvexPolygon, Point};
use crate::layout::map::{MapSettings, MapSimulation};
use crate::layout::method::Method;
use crate::layout::treemap::{child_targets, child_targets_within};
use crate::layout::{seed, Params};
use crate::neighborhood::matching;
use crate::rng::Rng;
use nptreemap_formats::Dataset;

/// The CVT stops early once no site moved more than this share of a cell's
/// size (square root of the mean cell area) in a Lloyd step: the sites are
/// as evenly spread as matching needs.
const CVT_SETTLED: f64 = 0.01;
/// Diagrams of more children than this get at most [`LARGE_CVT_TICKS`] CVT
/// steps. Their slowest site never settles within the 40 of
/// [`NeighborParams::cvt_iterations`] (each a power diagram of every cell:
/// 2.4 s of a 10,000-cell flat layout's 8 s), and from the Halton start ten
/// steps spread the sites as evenly as matching needs: on flat10000 the
/// realised constraints were 6,950 after 10 steps and 6,223 after 40 (both
/// without attraction ticks, seed 1; the difference is the start's luck).
/// From 1,000 children on, the same holds (seeds 1–5, median realised
/// constraints with 10 steps against 40: `tests/data/real/usr-bin`, 1,061
/// cells, 974 against 951; flat2000 1,564 against 1,561), and the CVT was a
/// fifth of flat2000's layout time.
const CVT_FULL_MAX_CELLS: usize = 1000;
const LARGE_CVT_TICKS: usize = 10;

/// Independent starts per level for `neighbor`: a level is cheap when small,
/// and its best start is kept (the level's score decides). Enough starts to
/// spend about `start_budget` cell-starts, between 1 and `max_starts`.
pub(super) fn starts_for(level_size: usize, np: &NeighborParams) -> usize {
    (np.start_budget / level_size.max(1)).clamp(1, np.max_starts.max(1))
}

/// The target areas of `parent`'s children inside `clip` while a level is
/// optimised: the configured floor for light children, whatever it costs the
/// areas (their cells keep room for neighbours; `retarget` gives them their
/// real areas once the arrangement is chosen).
pub(super) fn sim_targets(
    dataset: &Dataset,
    clip: &ConvexPolygon,
    parent: usize,
    params: &Params,
) -> Vec<f64> {
    child_targets_within(dataset, parent, clip, params, f64::INFINITY).0
}

/// Builds one parent's diagram in its starting state for `method`.
#[allow(clippy::too_many_arguments)]
pub(super) fn init_diagram(
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
    // The baseline that starts at its areas has them final from the start.
    let (targets, slack) = child_targets(dataset, parent, &polygon, params);
    let (positions, weights) = if method == Method::ProjScale {
        let points: Vec<Point> = children.iter().map(|c| projected[*c]).collect();
        (project_and_scale(&polygon, &points, &mut rng), None)
    } else {
        let (site_pos, site_weights) = equal_area_cvt(&polygon, k, np, &mut rng);
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
        let weights = order.iter().map(|&s| site_weights[s]).collect();
        (positions, Some(weights))
    };
    // Similarity methods start from the CVT's equal areas; targets are set when
    // their optimisation starts, so swaps compare cells of the CVT geometry.
    let start_targets = if method == Method::ProjScale {
        targets
    } else {
        vec![polygon.area() / k as f64; k]
    };
    let mut sim = MapSimulation::new(polygon, start_targets, positions, weights, settings, rng);
    if method == Method::ProjScale {
        sim.set_slack(slack);
    }
    Diagram::Sim {
        children,
        sim: Box::new(sim),
    }
}

/// The equal-area CVT of `k` cells in `polygon` (method-reference §4.2): Lloyd
/// steps from well-spread sites, each with the Newton weight step that keeps
/// the areas equal, one power diagram per step. Returns sites and weights.
fn equal_area_cvt(
    polygon: &ConvexPolygon,
    k: usize,
    np: &NeighborParams,
    rng: &mut Rng,
) -> (Vec<Point>, Vec<f64>) {
    let equal = vec![polygon.area() / k as f64; k];
    let start = seed::halton_positions(polygon, k, rng);
    let settings = MapSettings {
        convergence_ratio: 0.0,
        max_iterations: np.cvt_iterations.max(1),
        min_iterations: np.cvt_iterations.max(1),
    };
    let mut cvt = MapSimulation::new(polygon.clone(), equal, start, None, settings, rng.clone());
    let settled = CVT_SETTLED * (polygon.area() / k as f64).sqrt();
    let ticks = if k > CVT_FULL_MAX_CELLS {
        np.cvt_iterations.clamp(1, LARGE_CVT_TICKS)
    } else {
        np.cvt_iterations.max(1)
    };
    for _ in 0..ticks {
        let before: Vec<Point> = cvt.state().sites.iter().map(|s| s.position).collect();
        cvt.relax_step(1.0);
        let moved = cvt
            .state()
            .sites
            .iter()
            .zip(&before)
            .map(|(s, b)| s.position.distance(*b))
            .fold(0.0, f64::max);
        if moved <= settled {
            break;
        }
    }
    let sites = cvt.state().sites;
    (
        sites.iter().map(|s| s.position).collect(),
        sites.iter().map(|s| s.weight).collect(),
    )
}

/// The projection-and-scale start of Nocaj and Brandes (method-reference §6.2):
/// move the points' hull centroid onto the parent's centroid, then shrink
/// towards it by factors 0.99, 0.89, …, 0.09 until every point is inside.
pub(super) fn project_and_scale(
    parent: &ConvexPolygon,
    points: &[Point],
    rng: &mut Rng,
) -> Vec<Point> {
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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn the_cvt_has_equal_areas() {
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 100.0, 60.0).expect("rect");
        let np = NeighborParams::default();
        let (pos, w) = equal_area_cvt(&clip, 30, &np, &mut Rng::new(4));
        let sites: Vec<_> = pos
            .iter()
            .zip(&w)
            .map(|(p, w)| crate::power::Site {
                position: *p,
                weight: *w,
            })
            .collect();
        let d = crate::power::power_diagram(&sites, &clip);
        let share = clip.area() / 30.0;
        for c in &d.cells {
            assert!(
                (c.area - share).abs() < 0.05 * share,
                "{} vs {share}",
                c.area
            );
        }
    }
}
