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
}

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
}

/// Repair rounds per diagram evaluation. One round fixes every empty cell seen;
/// more than a handful means pathological input, where the next tick goes on.
const REPAIR_ROUNDS: usize = 4;

/// Rounds of the quick repair (a dominated site's weight raised just below its
/// dominator's) before empty cells get [`MapSimulation::restart_site`]. The
/// quick fix is local but can cascade through chains of tiny cells beside huge
/// ones (weights 1:85,000 in the Debian packages of `tests/data/real`).
const QUICK_REPAIR_ROUNDS: usize = 2;

/// Rounds of [`MapSimulation::restart_empty`].
const RESTART_ROUNDS: usize = 3;

/// Random points tried by [`MapSimulation::restart_site`] after the site's own
/// position and its dominator's centroid.
const RESTART_TRIES: usize = 8;

/// A weight gap (upper minus lower bound, a squared length) wide enough to
/// stop [`MapSimulation::restart_site`]'s search, as a share of the clip's area.
const RESTART_MIN_GAP: f64 = 1e-9;

/// A dominated site's weight is raised to leave this share of the squared site
/// distance as margin, so the repaired site lies strictly inside its cell
/// (d3-voronoi-map's `handleOverweighted` uses the full distance plus epsilon).
const REPAIR_MARGIN: f64 = 0.9;

/// [`MapSimulation::prevent_domination`] keeps `w_j − w_i` below this share of
/// `d²`, so the bisector stays at least `(1 − margin)·d/2` from the site. A
/// small cell next to a big one needs its bisector close to its site (a 1:10⁴
/// area ratio needs about d/300), so the margin is thin; a wider one pinned
/// small corner cells above their target area.
const PREVENT_MARGIN: f64 = 0.999;

/// Passes of [`MapSimulation::prevent_domination`]; raising one weight can make
/// that site dominate another, which the next pass catches.
const PREVENT_PASSES: usize = 3;

/// Newton steps are shortened so no bisector moves by more than this share of
/// its site distance: the linearisation is good for moderate moves, and a site
/// is never overtaken by a neighbour's bisector in one step.
const MAX_BISECTOR_SHIFT: f64 = 1.0;

/// Halvings tried by the line search of [`MapSimulation::settle_weights`].
const LINE_SEARCH_HALVINGS: usize = 12;

/// Smallest share of the Newton step taken while the error oscillates.
const MIN_DAMPING: f64 = 1.0 / 16.0;

/// Conjugate-gradient stop: residual below this share of the right-hand side.
/// The step is re-linearised next tick anyway, so a rough solve is enough.
const CG_TOLERANCE: f64 = 1e-3;

/// Conjugate-gradient iteration cap (a 2-D Laplacian of n cells needs about √n).
const CG_MAX_ITER: usize = 200;

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
        };
        sim.repair();
        sim.error = sim.area_error();
        sim
    }

    /// One step: Lloyd move, diagram, Newton weight step, diagram.
    pub fn tick(&mut self) {
        if self.ended {
            return;
        }
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
        let converged =
            self.error <= self.area_target() && self.iteration >= self.settings.min_iterations;
        if converged || self.iteration >= self.settings.max_iterations {
            self.ended = true;
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

    /// Gives every site with an empty cell a new start (`restart_site`)
    /// and recomputes the diagram, a few rounds at most; returns how many
    /// sites were restarted. For the end of an optimisation, where a cell left
    /// empty would make the layout fail.
    pub fn restart_empty(&mut self) -> usize {
        let mut restarted = 0;
        for _ in 0..RESTART_ROUNDS {
            let empty: Vec<usize> = (0..self.sites.len())
                .filter(|&i| self.diagram.cells[i].polygon.is_none())
                .collect();
            if empty.is_empty() {
                break;
            }
            for &i in &empty {
                self.restart_site(i);
            }
            restarted += empty.len();
            self.diagram = power_diagram(&self.sites, &self.clip);
        }
        self.error = self.area_error();
        restarted
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

    /// One step that moves only weights (sites stay put): the final settling
    /// of a layout whose site arrangement carries meaning, such as realised
    /// neighbourhoods. Returns the new area error.
    pub fn settle_weights(&mut self) -> f64 {
        // No `prevent_domination` here: with sites fixed, the weights that give
        // the target areas may leave a site outside its own cell, and forcing it
        // back in stalls the solve. Instead of the step cap, whose worst pair
        // can stall fixed sites, the full Newton step is tried and halved until
        // the area error drops (backtracking line search).
        self.iteration += 1;
        let Some((x, _)) = self.newton_direction() else {
            return self.error;
        };
        let base: Vec<f64> = self.sites.iter().map(|s| s.weight).collect();
        let mut alpha = 1.0;
        for _ in 0..LINE_SEARCH_HALVINGS {
            for ((site, w), dx) in self.sites.iter_mut().zip(&base).zip(&x) {
                site.weight = w + alpha * dx;
            }
            let diagram = power_diagram(&self.sites, &self.clip);
            let empty = diagram.cells.iter().any(|c| c.polygon.is_none());
            let error = area_error_of(&diagram, &self.targets, self.clip_area);
            if !empty && error < self.error {
                self.diagram = diagram;
                self.error = error;
                return error;
            }
            alpha *= 0.5;
        }
        // No step helped: keep the previous weights and diagram.
        for (site, w) in self.sites.iter_mut().zip(&base) {
            site.weight = *w;
        }
        self.error
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

    /// Before a new diagram: raise the weight of any site that a neighbour or
    /// its dominator in the previous diagram would swallow at the current
    /// positions. A cheap local version of d3-voronoi-map's all-pairs
    /// `handleOverweighted` (O(n²)); what it misses, [`Self::repair`] catches.
    fn prevent_domination(&mut self) {
        for _ in 0..PREVENT_PASSES {
            let mut changed = false;
            for i in 0..self.sites.len() {
                let cell = &self.diagram.cells[i];
                let others = cell
                    .neighbors
                    .iter()
                    .map(|nb| nb.site)
                    .chain(cell.dominated_by);
                for j in others {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    let floor = self.sites[j].weight - PREVENT_MARGIN * d2;
                    if self.sites[i].weight < floor {
                        self.sites[i].weight = floor;
                        changed = true;
                    }
                }
            }
            if !changed {
                return;
            }
        }
    }

    fn area_error(&self) -> f64 {
        area_error_of(&self.diagram, &self.targets, self.clip_area)
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

    /// Gives every site a non-empty cell, recomputing the diagram while any cell
    /// is empty: a dominated site's weight is raised to just below the level at
    /// which its dominator swallows it; an empty cell that is not dominated
    /// (coincident sites) gets a fresh random position. Sites that are dominated
    /// but still have a cell are left to [`Self::prevent_domination`] before the
    /// next diagram: fixing them here cascades (a raised site dominates the
    /// next), costing a full diagram per round.
    fn repair(&mut self) {
        for round in 0..REPAIR_ROUNDS {
            let mut changed = false;
            for i in 0..self.sites.len() {
                let cell = &self.diagram.cells[i];
                if cell.polygon.is_some() {
                    continue;
                }
                if round >= QUICK_REPAIR_ROUNDS {
                    // The quick fix cascades (a raised site swallows the
                    // next); give what is still empty a start that provably
                    // has a cell.
                    self.restart_site(i);
                    changed = true;
                    continue;
                }
                let dominator = cell.dominated_by.map(|j| {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    (j, d2)
                });
                match dominator {
                    // A dominator on the very same spot (coincident sites) cannot
                    // be escaped through weights.
                    Some((j, d2)) if d2 > 0.0 => {
                        self.sites[i].weight = self.sites[j].weight - REPAIR_MARGIN * d2;
                    }
                    _ => {
                        self.sites[i].position =
                            self.clip.sample(self.rng.next_f64(), self.rng.next_f64());
                    }
                }
                changed = true;
            }
            if !changed {
                return;
            }
            self.diagram = power_diagram(&self.sites, &self.clip);
        }
    }

    /// Gives site `i` a weight, and if need be a position, at which it owns a
    /// cell without swallowing any other site. At a point `p`, site `i` holds
    /// `p` against every other site `k` when `w_i > max_k (w_k − |p − p_k|²)`
    /// (the lower bound `lo`) and takes no other site's own point when `w_i <
    /// min_k (w_k + |p − p_k|²)` (the upper bound `hi`). The site stays where
    /// it is when the bounds leave room there; else it moves to the first of
    /// its dominator's centroid and a few seeded random points where they do
    /// (the widest gap if none is wide). O(n) per site, and only for sites
    /// whose cell the quick repair could not keep.
    fn restart_site(&mut self, i: usize) {
        let bounds = |sites: &[Site], p: Point| -> (f64, f64) {
            let mut lo = f64::NEG_INFINITY;
            let mut hi = f64::INFINITY;
            for (k, s) in sites.iter().enumerate() {
                if k == i || !(s.weight.is_finite() && s.position.is_finite()) {
                    continue;
                }
                let d2 = p.distance_squared(s.position);
                lo = lo.max(s.weight - d2);
                hi = hi.min(s.weight + d2);
            }
            (lo, hi)
        };
        let wide = RESTART_MIN_GAP * self.clip_area;
        let mut candidates = Vec::with_capacity(2);
        let here = self.sites[i].position;
        if here.is_finite() && self.clip.contains(here) {
            candidates.push(here);
        }
        if let Some(j) = self.diagram.cells[i].dominated_by {
            if self.diagram.cells[j].polygon.is_some() {
                candidates.push(self.diagram.cells[j].centroid);
            }
        }
        let mut best: Option<(f64, Point, f64)> = None;
        for k in 0..candidates.len() + RESTART_TRIES {
            let p = match candidates.get(k) {
                Some(p) => *p,
                None => self.clip.sample(self.rng.next_f64(), self.rng.next_f64()),
            };
            let (lo, hi) = bounds(&self.sites, p);
            // Infinite when there is no other site: any weight will do.
            let gap = hi - lo;
            if best.is_none_or(|b| gap > b.0) {
                best = Some((gap, p, lo));
            }
            if gap > wide {
                break;
            }
        }
        let Some((gap, p, lo)) = best else {
            return;
        };
        // Above the lower bound by what a free disc of the target area needs
        // (|x − p|² < w_i − lo), and never past half the gap.
        let weight = if gap.is_infinite() {
            0.0
        } else {
            lo + (self.targets[i] / std::f64::consts::PI).min(0.5 * gap.max(0.0))
        };
        self.sites[i] = Site {
            position: p,
            weight,
        };
    }

    /// Newton step on the power weights: solve `L Δw = A* − A` where `L` is the
    /// Laplacian with edge conductances `l_ij / (2 d_ij)`.
    fn newton_weights(&mut self) {
        if let Some((x, alpha)) = self.newton_direction() {
            for (site, dx) in self.sites.iter_mut().zip(&x) {
                site.weight += alpha * dx;
            }
        }
    }

    /// The Newton step on the weights and the capped step length (see
    /// `MAX_BISECTOR_SHIFT` and the flicker damping); `None` when there is
    /// nothing to solve.
    fn newton_direction(&self) -> Option<(Vec<f64>, f64)> {
        let n = self.sites.len();
        if n < 2 {
            return None;
        }
        // Conductances in compressed rows.
        let mut start = Vec::with_capacity(n + 1);
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        let mut diag = vec![0.0; n];
        for (i, cell) in self.diagram.cells.iter().enumerate() {
            start.push(cols.len());
            for nb in &cell.neighbors {
                let d = self.sites[i]
                    .position
                    .distance(self.sites[nb.site].position);
                let l = nb.edge[0].distance(nb.edge[1]);
                if d > 0.0 && l > 0.0 {
                    let c = l / (2.0 * d);
                    cols.push(nb.site);
                    vals.push(c);
                    diag[i] += c;
                }
            }
        }
        start.push(cols.len());
        let active: Vec<bool> = diag.iter().map(|d| *d > 0.0).collect();
        let mut b: Vec<f64> = (0..n)
            .map(|i| {
                if active[i] {
                    self.targets[i] - self.diagram.cells[i].area
                } else {
                    0.0
                }
            })
            .collect();
        // The Laplacian is singular (adding a constant to every weight changes
        // nothing); a consistent right-hand side sums to zero.
        let count = active.iter().filter(|a| **a).count();
        if count < 2 {
            return None;
        }
        let mean = b.iter().sum::<f64>() / count as f64;
        for (bi, a) in b.iter_mut().zip(&active) {
            if *a {
                *bi -= mean;
            }
        }
        let apply = |x: &[f64], out: &mut [f64]| {
            for i in 0..n {
                let mut s = diag[i] * x[i];
                for k in start[i]..start[i + 1] {
                    s -= vals[k] * x[cols[k]];
                }
                out[i] = s;
            }
        };
        let x = conjugate_gradient(&b, &diag, apply);
        // Shorten the step so no bisector moves too far (see MAX_BISECTOR_SHIFT).
        let mut alpha: f64 = self.damping;
        for i in 0..n {
            for &j in &cols[start[i]..start[i + 1]] {
                let dw = (x[i] - x[j]).abs();
                if dw > 0.0 {
                    let d2 = self.sites[i]
                        .position
                        .distance_squared(self.sites[j].position);
                    alpha = alpha.min(2.0 * MAX_BISECTOR_SHIFT * d2 / dw);
                }
            }
        }
        Some((x, alpha))
    }
}

/// Σ|A − A*| / A(clip) of a diagram.
fn area_error_of(diagram: &PowerDiagram, targets: &[f64], clip_area: f64) -> f64 {
    let sum: f64 = diagram
        .cells
        .iter()
        .zip(targets)
        .map(|(c, t)| (c.area - t).abs())
        .sum();
    sum / clip_area
}

/// Jacobi-preconditioned conjugate gradients for `L x = b` with `L` symmetric
/// positive semi-definite and `b` in its range. Rows with a zero diagonal are
/// left at 0.
fn conjugate_gradient(b: &[f64], diag: &[f64], apply: impl Fn(&[f64], &mut [f64])) -> Vec<f64> {
    let n = b.len();
    let inv: Vec<f64> = diag
        .iter()
        .map(|d| if *d > 0.0 { 1.0 / d } else { 0.0 })
        .collect();
    let dot = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(x, y)| x * y).sum::<f64>();
    let mut x = vec![0.0; n];
    let mut r = b.to_vec();
    let b_norm = dot(b, b).sqrt();
    if b_norm == 0.0 {
        return x;
    }
    let mut z: Vec<f64> = r.iter().zip(&inv).map(|(r, m)| r * m).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; n];
    for _ in 0..CG_MAX_ITER {
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let a = rz / pap;
        for i in 0..n {
            x[i] += a * p[i];
            r[i] -= a * ap[i];
        }
        if dot(&r, &r).sqrt() <= CG_TOLERANCE * b_norm {
            break;
        }
        for i in 0..n {
            z[i] = r[i] * inv[i];
        }
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    x
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
    fn conjugate_gradient_solves_a_path_laplacian() {
        // Path 0 - 1 - 2 with unit conductances; b sums to zero.
        let diag = [1.0, 2.0, 1.0];
        let apply = |x: &[f64], out: &mut [f64]| {
            out[0] = x[0] - x[1];
            out[1] = 2.0 * x[1] - x[0] - x[2];
            out[2] = x[2] - x[1];
        };
        let b = [1.0, 0.0, -1.0];
        let x = conjugate_gradient(&b, &diag, apply);
        let mut lx = [0.0; 3];
        apply(&x, &mut lx);
        for (l, b) in lx.iter().zip(b) {
            assert!((l - b).abs() < 1e-9, "{lx:?}");
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
