//! Our joint optimisation of one level (paper Algorithm 1, with the changes
//! of method-reference §10): every tick the level's neighbourhoods are read
//! from one snapshot and every diagram makes one step, each cell an attraction
//! move (Algorithm 2) plus a pull towards its centroid, with the Newton weight
//! step that keeps areas at their targets, usually one power diagram per step.
//!
//! The tick budget follows progress: the snapshot every tick reads gives the
//! level's score for free, the best state is kept (as a checkpoint of its
//! sites, not a copy of its cells), and the level stops once the score has not
//! risen by a meaningful step for a while ([`patience`]). Then a damped Lloyd
//! relaxation is kept while the score holds, swap rounds are kept while they
//! raise it, and the areas are settled.

use rayon::prelude::*;

use super::attract::attraction_moves;
use super::level::{settle, settle_to, Diagram, LevelCtx, Snapshot};
use super::links::Score;
use super::params::Distances;
use super::flip::{apply_flips, plan_flips, Flip};
use super::swap::{apply_swaps, pays, plan_swaps, swap_round};
use super::NeighborParams;
use crate::layout::frames::Recorder;
use crate::layout::map::Checkpoint;

/// Most Lloyd ticks per diagram that let the cells grow from the equal-area CVT
/// to their real areas before attraction starts, and the area error that ends
/// them. With weights 1:85,000 (`tests/data/real/debian-packages`) the weights
/// alone cannot get there: a cell that must grow 900-fold has its neighbours'
/// sites in the way, and the Newton step's bisector cap shrinks to a few
/// percent; Lloyd steps move the sites out of the way, keeping the matched
/// arrangement, as the plain layout does from its start.
const GROW_TICKS: usize = 40;
const GROWN_ERROR: f64 = 0.02;
/// A state is a candidate for the best only once every diagram's area error
/// is at most this: before the weights have caught up with the real targets,
/// neighbourhoods are not yet those of the finished cells.
const CANDIDATE_ERROR: f64 = 0.05;
/// A tick counts as progress when it lifts the best score by at least half a
/// constraint, or by this share of the score on large levels (where single
/// constraints keep trickling in long after the arrangement has settled).
const PLATEAU_SHARE: f64 = 0.002;
/// Levels of up to this many cells get the whole tick budget (patience grows
/// as levels shrink, see [`patience`]): their best moment is often brief and
/// late, and their ticks are cheap.
const PATIENT_CELLS: usize = 256;
/// Most Lloyd ticks of the final relaxation, and the share of the way to the
/// centroid each goes.
const RELAX_TICKS: usize = 30;
const RELAX_STEP: f64 = 0.5;
/// Most swap rounds tried on the final state (each kept only if it helps;
/// they stop once a round gains less than a tick must to count as progress).
const POLISH_ROUNDS: usize = 16;
/// Polish swaps only exchange cells whose target areas are within this ratio
/// (halved, down to the second, after a round whose areas did not settle).
const POLISH_MAX_RATIO: f64 = 4.0;
const POLISH_MIN_RATIO: f64 = 1.5;
/// Most flip rounds (paper §9) after the swap rounds, each kept only if it helps.
const FLIP_ROUNDS: usize = 4;
/// Most weight-only steps settling the areas after a polish round.
const POLISH_SETTLE: usize = 10;
/// A level with a diagram of more children than this skips the attraction
/// ticks and is arranged by the swap rounds of [`polish`] alone. In one flat
/// diagram of 10,000 cells (`benches/scale.py` flat10000) the ticks cost a
/// power diagram of the whole level each and lowered the score until the
/// next swap round (3,380 at tick 0, 2,777 at tick 15). Once the polish's
/// swaps kept their cells (`MapSimulation::swap_sites`), the ticks stopped
/// paying above a few hundred cells: over seeds 1–5, without them the
/// median realised constraints were 951 instead of 944 on
/// `tests/data/real/usr-bin` (1,061 cells, weights 1:10⁵), 1,561 instead of
/// 1,559 on flat2000 and 443 instead of 437 on `debian-packages`, in half
/// the time or less; below the bound they still pay (`man-pages` 1,213
/// with them, 1,170 without; `python-stdlib` 577 and 557). BENCHMARKS.md,
/// "Attraction ticks on large diagrams".
const ATTRACT_MAX_CHILDREN: usize = 300;
/// The finished level's areas are settled to this share of the run's area
/// target (the cells are final; the target is for diagrams still moving).
const FINAL_SHARE: f64 = 0.1;

/// Why an optimisation stopped early: the progress callback said so.
#[derive(Debug)]
pub(super) struct Stopped;

/// A level's state, diagram by diagram (`None` for only children).
type Saved = Vec<Option<Checkpoint>>;

fn save(diagrams: &[Diagram]) -> Saved {
    diagrams
        .par_iter()
        .map(|d| match d {
            Diagram::Sim { sim, .. } => Some(sim.checkpoint()),
            Diagram::Single { .. } => None,
        })
        .collect()
}

fn restore(diagrams: &mut [Diagram], saved: &Saved) {
    diagrams
        .par_iter_mut()
        .zip(saved.par_iter())
        .for_each(|(d, s)| {
            if let (Diagram::Sim { sim, .. }, Some(s)) = (d, s) {
                sim.restore(s);
            }
        });
}

/// Ticks without progress after which a level of `cells` cells stops:
/// `np.patience` on large levels, the whole budget on small ones, in between
/// in proportion.
fn patience(cells: usize, np: &NeighborParams) -> usize {
    if np.patience == 0 {
        return usize::MAX;
    }
    let scaled = np.ticks * PATIENT_CELLS / cells.max(1);
    np.patience.max(scaled)
}

/// Optimises one level from its matched-and-swapped start (targets already
/// set to the real areas) and returns the score and diagrams of the best state
/// found, relaxed, polished and settled. `tick_done(t)` is told after every
/// tick and returns false to stop.
pub(super) fn optimize_level(
    mut diagrams: Vec<Diagram>,
    lv: &LevelCtx<'_>,
    mut recorder: Option<&mut Recorder>,
    tick_done: &dyn Fn(usize) -> bool,
) -> Result<(Score, Vec<Diagram>), Stopped> {
    let np = lv.np;
    // The unit length of the level: square root of its mean cell area.
    let total: f64 = diagrams.iter().map(|d| d.clip().area()).sum();
    let cells = lv.links.nodes.len();
    let unit = (total / cells.max(1) as f64).sqrt();
    let limits = Distances::relative(unit, np);
    tracing::debug!(cells, diagrams = diagrams.len(), "level start");
    grow(&mut diagrams);
    tracing::debug!("level grown");
    let patience = patience(cells, np);
    let mut best: Option<(Score, Saved)> = None;
    let mut progress = Progress::default();
    // One diagram this large is arranged by the swap rounds of `polish`, not
    // by attraction ticks (see ATTRACT_MAX_CHILDREN).
    let largest = diagrams.iter().map(Diagram::len).max().unwrap_or(0);
    let ticks = if largest > ATTRACT_MAX_CHILDREN {
        lloyd_until(&mut diagrams, CANDIDATE_ERROR, np.ticks);
        0
    } else {
        np.ticks
    };
    let mut ticks_run = 0;
    for tick in 0..ticks {
        ticks_run = tick + 1;
        if np.swap_every > 0 && tick > 0 && tick % np.swap_every == 0 && tick + 20 < np.ticks {
            swap_round(&mut diagrams, lv);
            grow(&mut diagrams);
        }
        let snap = lv.snapshot(&diagrams);
        keep_if_best(&mut best, &snap.score, snap.area_error, &diagrams);
        let value = best.as_ref().map(|b| b.0.value());
        if progress.observe(value) >= patience {
            break;
        }
        diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { children, sim } = d {
                if sim.state().convergence_ratio > CANDIDATE_ERROR {
                    // The areas fell behind the moves: let them catch up.
                    sim.lloyd_tick();
                } else {
                    let positions = attraction_moves(children, sim, lv.links, &snap, &limits, true);
                    sim.step_with_positions(&positions);
                }
            }
        });
        if let Some(r) = recorder.as_deref_mut().filter(|r| r.wants(tick)) {
            r.take(
                format!("tick {}", tick + 1),
                super::level::frame_cells(&diagrams),
            );
        }
        if !tick_done(tick + 1) {
            return Err(Stopped);
        }
    }
    let snap = lv.snapshot(&diagrams);
    keep_if_best(&mut best, &snap.score, snap.area_error, &diagrams);
    tracing::debug!(ticks_run, best = ?best.as_ref().map(|b| b.0.realized), "ticks done");
    let score = match best {
        Some((score, saved)) => {
            restore(&mut diagrams, &saved);
            score
        }
        None => snap.score,
    };
    let score = relax(&mut diagrams, score, lv);
    tracing::debug!(realized = score.realized, "relaxed");
    polish(&mut diagrams, score, lv);
    diagrams.par_iter_mut().for_each(|d| {
        if let Diagram::Sim { sim, .. } = d {
            let target = (FINAL_SHARE * sim.settings().convergence_ratio).min(sim.area_target());
            settle_to(d, np, target);
        }
    });
    let score = lv.snapshot(&diagrams).score;
    tracing::debug!(realized = score.realized, "level settled");
    Ok((score, diagrams))
}

/// Lloyd ticks (the plain optimiser's), at most `ticks`, for every diagram
/// whose area error is above `error`: after the equal-area start and after
/// swaps (to [`GROWN_ERROR`]), and for a level that makes no attraction
/// ticks, what the tick loop would do for it (to [`CANDIDATE_ERROR`]: after
/// growing, a 10,000-cell diagram can still be at area error 0.7).
fn lloyd_until(diagrams: &mut [Diagram], error: f64, ticks: usize) {
    diagrams.par_iter_mut().for_each(|d| {
        if let Diagram::Sim { sim, .. } = d {
            for _ in 0..ticks {
                if sim.state().convergence_ratio <= error {
                    break;
                }
                sim.lloyd_tick();
            }
        }
    });
}

/// [`lloyd_until`] the areas have grown from the equal-area start.
fn grow(diagrams: &mut [Diagram]) {
    lloyd_until(diagrams, GROWN_ERROR, GROW_TICKS);
}

/// The patience count of the tick loop: the best score that last counted as
/// progress, and the ticks since.
#[derive(Default)]
struct Progress {
    reference: Option<f64>,
    idle: usize,
}

impl Progress {
    /// Takes the best score after a tick (`None` while no state is a
    /// candidate yet) and returns the ticks since the last progress.
    fn observe(&mut self, best: Option<f64>) -> usize {
        // The first candidate is progress over nothing (a reference of -inf
        // would make the step, and so the comparison, NaN).
        let rises = |value: f64| self.reference.is_none_or(|r| value >= r + progress_step(r));
        match best {
            Some(value) if rises(value) => {
                self.reference = Some(value);
                self.idle = 0;
            }
            _ => self.idle += 1,
        }
        self.idle
    }
}

/// The least rise over `reference` that counts as progress: half a
/// constraint, or [`PLATEAU_SHARE`] of the score on large levels.
fn progress_step(reference: f64) -> f64 {
    (PLATEAU_SHARE * reference.abs()).max(0.5)
}

/// Keeps `diagrams` as the best state when its score is at least the best's
/// (ties go to the later state, which has had more optimisation) and its
/// areas are near their targets.
fn keep_if_best(
    best: &mut Option<(Score, Saved)>,
    score: &Score,
    area_error: f64,
    diagrams: &[Diagram],
) {
    if area_error <= CANDIDATE_ERROR && best.as_ref().is_none_or(|b| score.value() >= b.0.value()) {
        *best = Some((*score, save(diagrams)));
    }
}

/// Rounds the cells: damped Lloyd ticks on the chosen state, each kept only
/// while the level's score does not drop. The attraction phase moves sites
/// off their centroids (long cells); this takes back what the arrangement
/// does not need. Returns the score of the state kept.
fn relax(diagrams: &mut [Diagram], mut score: Score, lv: &LevelCtx<'_>) -> Score {
    for _ in 0..RELAX_TICKS {
        let saved = save(diagrams);
        diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { sim, .. } = d {
                sim.relax_step(RELAX_STEP);
            }
        });
        let snap = lv.snapshot(diagrams);
        if snap.score.value() < score.value() || snap.area_error > CANDIDATE_ERROR {
            restore(diagrams, &saved);
            break;
        }
        score = snap.score;
    }
    score
}

/// Swap rounds on the chosen state with its areas settled, then flip rounds
/// ([`plan_flips`], paper §9). A swap round is kept while it raises the
/// level's score, read from the snapshot the next round plans on (one
/// snapshot per round). Each flip is judged by its own neighbourhood once
/// its round is settled ([`pays`]): those that did not pay are moved back
/// and the round settled again; a round that lowers the level's score after
/// all is undone. (Judging the swaps the same way realised no more: the
/// settling of a round moves adjacencies far from its swaps; see
/// BENCHMARKS.md, "Local moves and spade".)
fn polish(diagrams: &mut [Diagram], mut score: Score, lv: &LevelCtx<'_>) {
    // Weight-only settling after a round of exchanges of cells of similar
    // size converges in a few steps; its full budget (and exchanges of very
    // different cells, which it cannot settle with the sites held) is what
    // made a round on a 10,000-cell diagram cost tens of seconds.
    let np = NeighborParams {
        settle_iterations: POLISH_SETTLE.min(lv.np.settle_iterations),
        ..lv.np.clone()
    };
    let mut max_ratio = POLISH_MAX_RATIO;
    let mut snap = lv.snapshot(diagrams);
    let mut flips_left = FLIP_ROUNDS;
    let mut swapping = true;
    for round in 0..POLISH_ROUNDS + FLIP_ROUNDS {
        swapping &= round < POLISH_ROUNDS;
        let saved = save(diagrams);
        if swapping {
            let pairs = plan_swaps(diagrams, &snap, lv, max_ratio);
            if pairs.is_empty() {
                swapping = false;
                continue;
            }
            apply_swaps(diagrams, &snap, &pairs);
            diagrams.par_iter_mut().for_each(|d| settle(d, &np));
            tracing::debug!(round, swaps = pairs.len(), "polish swaps");
        } else {
            if flips_left == 0 {
                break;
            }
            flips_left -= 1;
            let flips = plan_flips(diagrams, &snap, lv);
            let pairs: Vec<(usize, usize)> = flips.iter().map(|f| (f.a, f.b)).collect();
            if pairs.is_empty() {
                break;
            }
            apply_flips(diagrams, &snap, &flips, false);
            settle_touched(diagrams, &snap, &pairs, &np);
            let place: Vec<usize> = (0..lv.links.nodes.len()).collect();
            let unpaid: Vec<Flip> = flips
                .into_iter()
                .filter(|f| !pays(diagrams, &snap, &[f.a, f.b], &place, lv))
                .collect();
            tracing::debug!(round, flips = pairs.len(), unpaid = unpaid.len(), "polish flips");
            if unpaid.len() == pairs.len() {
                restore(diagrams, &saved);
                break;
            }
            let back: Vec<(usize, usize)> = unpaid.iter().map(|f| (f.a, f.b)).collect();
            apply_flips(diagrams, &snap, &unpaid, true);
            settle_touched(diagrams, &snap, &back, &np);
        }
        let next = lv.snapshot(diagrams);
        if swapping && next.area_error > CANDIDATE_ERROR && max_ratio > POLISH_MIN_RATIO {
            // Some exchange could not be settled: retry with closer sizes.
            restore(diagrams, &saved);
            max_ratio = (max_ratio / 2.0).max(POLISH_MIN_RATIO);
            continue;
        }
        if next.score.value() <= score.value() || next.area_error > CANDIDATE_ERROR {
            tracing::debug!(round, swapping, realized = next.score.realized, was = score.realized, area_error = next.area_error, "polish round undone");
            restore(diagrams, &saved);
            if swapping {
                swapping = false;
                continue;
            }
            break;
        }
        let gain = next.score.value() - score.value();
        tracing::debug!(round, swapping, gain, realized = next.score.realized, "polish round kept");
        score = next.score;
        snap = next;
        if gain < progress_step(score.value()) {
            if swapping {
                swapping = false;
                continue;
            }
            break;
        }
    }
}

/// Settles the areas of the diagrams holding a pair of `pairs`.
fn settle_touched(
    diagrams: &mut [Diagram],
    snap: &Snapshot,
    pairs: &[(usize, usize)],
    np: &NeighborParams,
) {
    let mut touched = vec![false; diagrams.len()];
    for &(a, _) in pairs {
        touched[snap.diagram[a]] = true;
    }
    diagrams
        .par_iter_mut()
        .zip(touched.par_iter())
        .filter(|(_, t)| **t)
        .for_each(|(d, _)| settle(d, np));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_candidate_and_each_real_rise_count_as_progress() {
        let mut p = Progress::default();
        // Before any candidate state, ticks are idle.
        assert_eq!(p.observe(None), 1);
        assert_eq!(p.observe(None), 2);
        // The first candidate is progress over nothing.
        assert_eq!(p.observe(Some(100.0)), 0);
        // Less than half a constraint more is not progress ...
        assert_eq!(p.observe(Some(100.4)), 1);
        // ... half a constraint over the last progress is.
        assert_eq!(p.observe(Some(100.5)), 0);
        // On large scores the step is PLATEAU_SHARE of the score.
        assert_eq!(p.observe(Some(10_000.0)), 0);
        assert_eq!(p.observe(Some(10_000.0 + 0.9 * PLATEAU_SHARE * 10_000.0)), 1);
        assert_eq!(p.observe(Some(10_000.0 + 1.1 * PLATEAU_SHARE * 10_000.0)), 0);
    }
}
