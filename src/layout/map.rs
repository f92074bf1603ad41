//! `MapSimulation`: one level of a Voronoi treemap, i.e. sites inside one parent
//! cell whose power-diagram cells must reach target areas. Driven step by step
//! with `MapSimulation::tick` and inspected with `MapSimulation::state`
//! (the d3-voronoi-map shape: the caller owns the clock).
//!
//! One tick is a Lloyd step (sites to their cells' centroids) followed by a
//! Newton step on the power weights. d3-voronoi-map and the paper's prototype
//! scale each weight by its area ratio, clamped to ±10% a tick, so n cells need
//! many ticks and large diagrams stop converging (peers/README.md: from about
//! 500 siblings). Here the weight step solves the linearised area equations
//! exactly instead: moving the bisector of sites i and j changes both areas by
//! `l_ij / (2 d_ij)` per unit of weight difference (edge length `l`, site distance
//! `d`), so the Jacobian of the areas in the weights is a graph Laplacian, solved
//! by preconditioned conjugate gradients in near-linear time (Nocaj and Brandes,
//! "Computing Voronoi treemaps", 2012, motivate the same weight/area coupling).

use crate::geom::{ConvexPolygon, Point};
use crate::power::{power_diagram, PowerDiagram, Site};
use crate::rng::Rng;

/// Keeping every cell non-empty.
mod repair;
/// The Newton weight step and the weight-only settle.
mod newton;
/// The capacity-constrained rounds after a stall.
mod rounds;

/// Smallest share of the Newton step taken while the error oscillates.
const MIN_DAMPING: f64 = 1.0 / 16.0;

/// Stopping rules of one diagram.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSettings {
    /// Converged when Σ|A − A*| / A(clip) is at most this.
    pub convergence_ratio: f64,
    /// Hard stop after this many ticks.
    pub max_iterations: usize,
    /// Ticks made before convergence may stop the run (shape relaxation).
    pub min_iterations: usize,
}

/// What [`MapSimulation::state`] reports.
#[derive(Clone, Copy, Debug)]
pub struct MapState<'a> {
    /// True once converged or out of iterations.
#[cfg_attr(not(any(test, feature = "internals")), allow(dead_code))]
    pub ended: bool,
    /// Ticks done.
    pub iteration_count: usize,
    /// Current Σ|A − A*| / A(clip).
    pub convergence_ratio: f64,
    /// Current sites.
    pub sites: &'a [Site],
    /// Current diagram of those sites.
    pub diagram: &'a PowerDiagram,
}

/// The optimiser for one diagram.
#[derive(Clone, Debug)]
pub struct MapSimulation {
    clip: ConvexPolygon,
    clip_area: f64,
    targets: Vec<f64>,
    sites: Vec<Site>,
    diagram: PowerDiagram,
    iteration: usize,
    error: f64,
    ended: bool,
    settings: MapSettings,
    rng: Rng,
    /// Share of the Newton step taken, lowered while the error oscillates.
    damping: f64,
    /// How far the targets' shares are from the weights' (a floor for tiny
    /// weights, `treemap::floored_targets`): the convergence test leaves it
    /// out of the ratio, so a converged diagram is within the ratio of its
    /// real weights.
    slack: f64,
    /// How the Lloyd ticks are doing (see [`STALL_TICKS`]).
    progress: Progress,
}

/// Where [`MapSimulation::tick`] stands: Lloyd ticks while they bring the
/// error down, then capacity-constrained rounds.
#[derive(Clone, Copy, Debug)]
struct Progress {
    /// The error when the Lloyd ticks last made progress.
    error: f64,
    /// Lloyd ticks since then.
    stalled: usize,
    /// Set once they stalled: the remaining ticks are rounds
    /// (`MapSimulation::transport_round`).
    settling: bool,
    /// Rounds made since then.
    rounds: usize,
}

impl Progress {
    const START: Progress = Progress {
        error: f64::INFINITY,
        stalled: 0,
        settling: false,
        rounds: 0,
    };
}

/// Lloyd ticks past `min_iterations` that may pass without the error falling
/// to [`STALL_PROGRESS`] of what it was before [`MapSimulation::tick`] gives
/// up on them and makes rounds instead. A Lloyd move shifts every bisector,
/// which a cell of 1:10⁵ of its neighbour's area cannot absorb: with half the
/// weights zero (floored) and a heavy tail, the Lloyd ticks held the error
/// near 1.6 for 50 ticks and ran to the cap (issue 34). A round solves the
/// weights to the target with Newton steps and a line search (the
/// semi-discrete optimal transport solve, Kitagawa, Mérigot and Thibert 2019,
/// which converges from any distinct sites) after each move.
const STALL_TICKS: usize = 4;

/// See [`STALL_TICKS`]: halving the error counts as progress.
const STALL_PROGRESS: f64 = 0.5;

/// Rounds ([`MapSimulation::transport_round`]) made after a stall before the
/// diagram may end: each moves the sites to their centroids and solves the
/// weights again, so the cells relax toward a centroidal power diagram while
/// their areas stay right. Fewer leave the cells that the stalled Lloyd ticks
/// bent: mean leaf aspect on `tests/data/real/usr-bin` 1.71 after 1 round,
/// 1.46 after 4, 1.33 after 8, 1.31 after 16 (1.28 in the 118 Lloyd ticks
/// of the engine before issue 34, 2.97 with weight-only steps); a round
/// costs about 5–10 diagrams.
const MIN_ROUNDS: usize = 16;

/// A saved state of a [`MapSimulation`]: its sites and counters, not its
/// diagram, which the sites determine ([`MapSimulation::restore`] recomputes
/// it, bit for bit). Much smaller than a copy of the simulation, so an
/// optimiser can keep its best state every tick.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    sites: Vec<Site>,
    iteration: usize,
    error: f64,
    ended: bool,
    rng: Rng,
    damping: f64,
    progress: Progress,
}



impl MapSimulation {
    /// A simulation of `positions.len()` sites in `clip` with target areas
    /// `targets` (same length; they should sum to the clip's area). `weights`
    /// are the starting power weights, or equal weights when `None`.
    pub fn new(
        clip: ConvexPolygon,
        targets: Vec<f64>,
        positions: Vec<Point>,
        weights: Option<Vec<f64>>,
        settings: MapSettings,
        rng: Rng,
    ) -> Self {
        debug_assert_eq!(targets.len(), positions.len());
        let weights = weights.unwrap_or_else(|| vec![0.0; positions.len()]);
        let sites = positions
            .into_iter()
            .zip(weights)
            .map(|(position, weight)| Site { position, weight })
            .collect::<Vec<_>>();
        let clip_area = clip.area();
        let diagram = power_diagram(&sites, &clip);
        let mut sim = Self {
            clip,
            clip_area,
            targets,
            sites,
            diagram,
            iteration: 0,
            error: f64::INFINITY,
            ended: false,
            settings,
            rng,
            damping: 1.0,
            slack: 0.0,
            progress: Progress::START,
        };
        sim.repair();
        sim.error = sim.area_error();
        sim
    }

    /// One step: Lloyd move, diagram, Newton weight step, diagram; once the
    /// Lloyd ticks stall ([`STALL_TICKS`]), a capacity-constrained round
    /// instead, at least [`MIN_ROUNDS`] of them.
    pub fn tick(&mut self) {
        if self.ended {
            return;
        }
        if self.progress.settling {
            self.transport_round();
        } else {
            self.lloyd_newton_tick();
        }
        let shaped = !self.progress.settling || self.progress.rounds >= MIN_ROUNDS;
        let converged = self.error <= self.area_target()
            && self.iteration >= self.settings.min_iterations
            && shaped;
        if converged || self.iteration >= self.settings.max_iterations {
            self.ended = true;
        }
    }

    /// [`Self::tick`]'s Lloyd tick, with its flicker damping and the watch
    /// for a stall.
    fn lloyd_newton_tick(&mut self) {
        self.move_to_centroids();
        self.recompute();
        self.newton_weights();
        self.recompute();
        self.iteration += 1;
        let previous = self.error;
        self.error = self.area_error();
        // Flicker mitigation (d3-voronoi-map's `flickeringMitigation` plays the
        // same role): past the relaxation ticks, whose site moves raise the
        // error by design, a tick that made the error worse halves the next
        // weight step; good ticks win the step length back.
        let relaxed = self.iteration > self.settings.min_iterations;
        self.damping = if relaxed && self.error > previous {
            (self.damping * 0.5).max(MIN_DAMPING)
        } else {
            (self.damping * 2.0).min(1.0)
        };
        if self.iteration < self.settings.min_iterations || self.error <= self.area_target() {
            return;
        }
        let p = &mut self.progress;
        if self.error <= STALL_PROGRESS * p.error {
            p.error = self.error;
            p.stalled = 0;
        } else {
            p.stalled += 1;
            p.settling = p.stalled >= STALL_TICKS;
        }
    }

    /// [`Self::tick`]'s Lloyd and weight steps whether or not the simulation
    /// has ended, without its stopping rules and flicker damping: for an
    /// optimiser that drives the simulation itself (the neighbourhood layout
    /// lets cells grow to their areas with it).
    pub fn lloyd_tick(&mut self) {
        self.move_to_centroids();
        self.recompute();
        self.newton_weights();
        self.recompute();
        self.iteration += 1;
        self.error = self.area_error();
    }

    /// One step with positions chosen by the caller (the neighbourhood
    /// optimiser's attraction moves) instead of the Lloyd step: the new
    /// positions, a diagram, a Newton weight step, a diagram. Positions must lie
    /// inside the clip. Counts as a tick but never ends the simulation.
    #[cfg(any(test, feature = "internals"))]
    pub fn tick_with_positions(&mut self, positions: &[Point]) {
        for (site, p) in self.sites.iter_mut().zip(positions) {
            site.position = *p;
        }
        self.recompute();
        self.newton_weights();
        self.recompute();
        self.iteration += 1;
        self.error = self.area_error();
    }

    /// One step with positions chosen by the caller, usually for one power
    /// diagram instead of [`Self::tick_with_positions`]'s two: the Newton
    /// weight step is taken from the current diagram (linearised at the old
    /// positions) together with the move, then the diagram is recomputed once;
    /// only when that leaves the area error above the convergence target does
    /// a second weight step follow. The state stays consistent (the diagram is
    /// always that of the current sites). Positions must lie inside the clip.
    /// Counts as a tick but never ends the simulation.
    pub fn step_with_positions(&mut self, positions: &[Point]) {
        let step = self.newton_direction();
        for (site, p) in self.sites.iter_mut().zip(positions) {
            site.position = *p;
        }
        if let Some((x, alpha)) = step {
            for (site, dx) in self.sites.iter_mut().zip(&x) {
                site.weight += alpha * dx;
            }
        }
        self.recompute();
        self.error = self.area_error();
        if self.error > self.settings.convergence_ratio {
            // The areas fell behind (a move too big for the step taken from
            // the old diagram): a second weight step from the new one.
            self.newton_weights();
            self.recompute();
            self.error = self.area_error();
        }
        self.iteration += 1;
    }

    /// A damped Lloyd step for [`Self::step_with_positions`]: every site goes
    /// `share` of the way to its cell's centroid (a site with an empty cell
    /// that nothing dominates, i.e. one on top of another, to a fresh random
    /// point, as in [`Self::tick`]).
    pub fn relax_step(&mut self, share: f64) {
        let positions: Vec<Point> = self
            .sites
            .iter()
            .zip(&self.diagram.cells)
            .map(|(s, c)| {
                if c.polygon.is_some() {
                    s.position + (c.centroid - s.position) * share
                } else if c.dominated_by.is_none() {
                    self.clip.sample(self.rng.next_f64(), self.rng.next_f64())
                } else {
                    s.position
                }
            })
            .collect();
        self.step_with_positions(&positions);
    }

    /// The number of sites whose cell is empty.
    pub fn empty_cells(&self) -> usize {
        self.diagram
            .cells
            .iter()
            .filter(|c| c.polygon.is_none())
            .count()
    }

    /// One step of the paper prototype's schedule (method-reference §5.9), for
    /// the `prototype` switch: the caller's positions, then either the weights
    /// reset to `reset_to` (before the growth phase) or d3-voronoi-map's
    /// multiplicative step (area ratio clamped to ±10%), then a diagram.
    /// Weights stay positive, as d3 keeps them.
    pub fn tick_prototype(&mut self, positions: &[Point], reset_to: Option<f64>) {
        for (site, p) in self.sites.iter_mut().zip(positions) {
            site.position = *p;
        }
        match reset_to {
            Some(w) => self.sites.iter_mut().for_each(|s| s.weight = w),
            None => {
                self.recompute();
                for (site, (cell, target)) in self
                    .sites
                    .iter_mut()
                    .zip(self.diagram.cells.iter().zip(&self.targets))
                {
                    if cell.area > 0.0 {
                        let ratio = (target / cell.area).clamp(0.9, 1.1);
                        site.weight = (site.weight * ratio).max(f64::MIN_POSITIVE);
                    }
                }
            }
        }
        self.recompute();
        self.iteration += 1;
        self.error = self.area_error();
    }


    /// Exchanges the sites (position and weight) of each pair of cells, and so
    /// their cells: node `a` takes over `b`'s place and vice versa (the swaps
    /// of method-reference §4.4), then recomputes the diagram once.
    pub fn swap_sites(&mut self, pairs: &[(usize, usize)]) {
        if pairs.is_empty() {
            return;
        }
        for &(a, b) in pairs {
            self.sites.swap(a, b);
        }
        // The same sites in other slots make the same diagram, relabelled, so
        // nothing can be swallowed; `prevent_domination` would read the old
        // diagram's adjacency by slot, now another site's, and raise weights
        // against cells far from the site (with weights 1:10⁵ that emptied
        // cells, and no weight-only settle could bring them back).
        self.diagram = power_diagram(&self.sites, &self.clip);
        self.repair();
        self.error = self.area_error();
    }

    /// Replaces the target areas (same length), e.g. after a CVT phase with
    /// equal areas. The ended flag is cleared so the run can continue.
    pub fn set_targets(&mut self, targets: Vec<f64>) {
        debug_assert_eq!(targets.len(), self.targets.len());
        self.targets = targets;
        self.error = self.area_error();
        self.ended = false;
    }

    /// The current state, to [`Self::restore`] later.
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            sites: self.sites.clone(),
            iteration: self.iteration,
            error: self.error,
            ended: self.ended,
            rng: self.rng.clone(),
            damping: self.damping,
            progress: self.progress,
        }
    }

    /// Goes back to a state saved by [`Self::checkpoint`] on this simulation
    /// (the same clip and targets), recomputing its diagram: the same diagram
    /// as when it was saved, since every diagram this simulation holds is the
    /// power diagram of its sites.
    pub fn restore(&mut self, saved: &Checkpoint) {
        self.sites.clone_from(&saved.sites);
        self.iteration = saved.iteration;
        self.error = saved.error;
        self.ended = saved.ended;
        self.rng = saved.rng.clone();
        self.damping = saved.damping;
        self.progress = saved.progress;
        self.diagram = power_diagram(&self.sites, &self.clip);
    }

    /// The target areas.
    pub fn targets(&self) -> &[f64] {
        &self.targets
    }

    /// The stopping rules.
    pub fn settings(&self) -> MapSettings {
        self.settings
    }

    /// The clip polygon.
    pub fn clip(&self) -> &ConvexPolygon {
        &self.clip
    }

    /// Ticks until the simulation ends.
    pub fn run(&mut self) {
        while !self.ended {
            self.tick();
        }
    }

    /// The current state.
    pub fn state(&self) -> MapState<'_> {
        MapState {
            ended: self.ended,
            iteration_count: self.iteration,
            convergence_ratio: self.error,
            sites: &self.sites,
            diagram: &self.diagram,
        }
    }

    /// True when the last evaluation met the convergence target.
    pub fn converged(&self) -> bool {
        self.error <= self.area_target()
    }

    /// The area error at which this diagram counts as converged: the
    /// convergence ratio less the slack ([`Self::set_slack`]).
    pub fn area_target(&self) -> f64 {
        (self.settings.convergence_ratio - self.slack).max(0.0)
    }

    /// The targets' own distance from the real weights' shares (Σ |share
    /// difference|), left out of the convergence ratio from now on; clears
    /// the ended flag when that moves the goal.
    pub fn set_slack(&mut self, slack: f64) {
        if slack != self.slack {
            self.slack = slack;
            self.ended = false;
        }
    }

    /// See [`Self::set_slack`].
    pub fn slack(&self) -> f64 {
        self.slack
    }

    /// The final sites and diagram.
    pub fn into_parts(self) -> (Vec<Site>, PowerDiagram) {
        (self.sites, self.diagram)
    }

    fn recompute(&mut self) {
        self.prevent_domination();
        self.diagram = power_diagram(&self.sites, &self.clip);
        self.repair();
    }


    /// Lloyd step. A site whose cell is empty cannot move to a centroid; one that
    /// is dominated is repaired through its weight, and any other (a site on top
    /// of another) is put at a fresh random point.
    fn move_to_centroids(&mut self) {
        for (site, cell) in self.sites.iter_mut().zip(&self.diagram.cells) {
            if cell.polygon.is_some() {
                site.position = cell.centroid;
            } else if cell.dominated_by.is_none() {
                site.position = self.clip.sample(self.rng.next_f64(), self.rng.next_f64());
            }
        }
    }

}


#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> MapSettings {
        MapSettings {
            convergence_ratio: 1e-4,
            max_iterations: 100,
            min_iterations: 3,
        }
    }

    #[test]
    fn two_sites_reach_a_one_to_three_split() {
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 4.0, 1.0).expect("rect");
        let positions = vec![Point::new(1.0, 0.5), Point::new(3.0, 0.5)];
        let mut sim = MapSimulation::new(
            clip,
            vec![1.0, 3.0],
            positions,
            None,
            settings(),
            Rng::new(1),
        );
        sim.run();
        let state = sim.state();
        assert!(state.ended && state.iteration_count < 100);
        assert!((state.diagram.cells[0].area - 1.0).abs() < 1e-3);
        assert!((state.diagram.cells[1].area - 3.0).abs() < 1e-3);
    }

    #[test]
    fn tick_counts_and_stops_at_the_cap() {
        let clip = ConvexPolygon::regular(Point::new(0.0, 0.0), 10.0, 6).expect("hexagon");
        let area = clip.area();
        let targets: Vec<f64> = (1..=7).map(|k| area * k as f64 / 28.0).collect();
        let mut rng = Rng::new(9);
        let positions = crate::layout::seed::halton_positions(&clip, 7, &mut rng);
        let capped = MapSettings {
            convergence_ratio: 0.0,
            max_iterations: 5,
            min_iterations: 0,
        };
        let mut sim = MapSimulation::new(clip.clone(), targets, positions, None, capped, rng);
        for k in 1..=5 {
            assert!(!sim.state().ended);
            sim.tick();
            assert_eq!(sim.state().iteration_count, k);
        }
        assert!(sim.state().ended);
        sim.tick();
        assert_eq!(
            sim.state().iteration_count,
            5,
            "ticks after the end do nothing"
        );
        let state = sim.state();
        state
            .diagram
            .sanity_check(state.sites, &clip)
            .expect("diagram sane");
        assert!(
            state.convergence_ratio < 0.05,
            "{}",
            state.convergence_ratio
        );
    }

    #[test]
    fn swapping_sites_exchanges_their_cells_and_nothing_else() {
        // Weights 1:10^4 (as in tests/data/real/usr-bin): a site that takes
        // over a small cell's place beside a huge one must keep exactly the
        // cell it took over. Exchanging sites only relabels the diagram, so
        // every cell's area moves with its site, unchanged.
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 100.0, 100.0).expect("rect");
        let n = 60;
        let mut rng = Rng::new(5);
        let raw: Vec<f64> = (0..n).map(|i| if i % 7 == 0 { 1e4 } else { 1.0 + (i % 5) as f64 }).collect();
        let total: f64 = raw.iter().sum();
        let targets: Vec<f64> = raw.iter().map(|r| clip.area() * r / total).collect();
        let positions = crate::layout::seed::halton_positions(&clip, n, &mut rng);
        let mut sim = MapSimulation::new(clip, targets, positions, None, settings(), rng);
        // Weights alone, sites held (as the polish settles): big cells'
        // weights then reach over their small neighbours' sites.
        for _ in 0..60 {
            sim.settle_weights();
        }
        assert!(sim.state().convergence_ratio < 0.01, "{}", sim.state().convergence_ratio);
        // Exchange small cells beside a big one with small cells elsewhere.
        let cells = &sim.state().diagram.cells;
        let small = |i: usize| i % 7 != 0;
        let mut pairs = Vec::new();
        let mut used = vec![false; n];
        for big in (0..n).step_by(7) {
            for nb in &cells[big].neighbors {
                let a = nb.site;
                let far = (0..n).find(|&b| {
                    small(b) && !used[b] && b != a && cells[b].neighbors.iter().all(|x| x.site != big)
                });
                if let Some(b) = far.filter(|_| small(a) && !used[a]) {
                    used[a] = true;
                    used[b] = true;
                    pairs.push((a, b));
                }
            }
        }
        assert!(pairs.len() >= 10, "{} pairs", pairs.len());
        let before: Vec<f64> = sim.state().diagram.cells.iter().map(|c| c.area).collect();
        sim.swap_sites(&pairs);
        let after: Vec<f64> = sim.state().diagram.cells.iter().map(|c| c.area).collect();
        let mut moved = before.clone();
        for &(a, b) in &pairs {
            moved.swap(a, b);
        }
        for (i, (m, a)) in moved.iter().zip(&after).enumerate() {
            assert!((m - a).abs() <= 1e-9 * m.max(1.0), "cell {i}: {a} after the swap, {m} expected");
        }
    }
}
