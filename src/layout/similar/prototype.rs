//! The paper prototype's optimisation of one level (method-reference
//! §5.2–5.10), for [`NeighborParams::prototype`](super::NeighborParams::prototype):
//! its fixed tick schedule, its weight handling and its pixel constants, kept
//! to reproduce the paper's own figures.

use rayon::prelude::*;

use super::attract::attraction_moves;
use super::level::{frame_cells, Diagram, LevelCtx};
use super::optimize::Stopped;
use super::params::Distances;
use super::swap::swap_round;
use crate::layout::frames::Recorder;

/// Ticks 0 to `np.ticks` inclusive; weights reset to the CVT's equal level
/// (area/2n, d3's `half-average-area`) until 45 ticks before the end, then
/// grown by d3's clamped multiplicative step; swap rounds at t = 20, 40, … up
/// to 20 ticks before the end; no attraction at t = 0 and in the last 10
/// ticks (pure 0.8 Lloyd there).
pub(super) fn optimize_prototype(
    diagrams: &mut [Diagram],
    lv: &LevelCtx<'_>,
    limits: &Distances,
    mut recorder: Option<&mut Recorder>,
    tick_done: &dyn Fn(usize) -> bool,
) -> Result<(), Stopped> {
    let np = lv.np;
    let last = np.ticks;
    let growth_from = last.saturating_sub(45);
    for tick in 0..=last {
        if np.swap_every > 0 && tick > 10 && tick % np.swap_every == 0 && tick + 20 < last {
            swap_round(diagrams, lv);
        }
        let snap = lv.snapshot(diagrams);
        let attract = tick >= 1 && tick + 10 <= last;
        diagrams.par_iter_mut().for_each(|d| {
            if let Diagram::Sim { children, sim } = d {
                let positions = attraction_moves(children, sim, lv.links, &snap, limits, attract);
                let reset =
                    (tick < growth_from).then(|| sim.clip().area() / (2.0 * children.len() as f64));
                sim.tick_prototype(&positions, reset);
            }
        });
        if let Some(r) = recorder.as_deref_mut().filter(|r| r.wants(tick)) {
            r.take(format!("tick {}", tick + 1), frame_cells(diagrams));
        }
        if !tick_done(tick + 1) {
            return Err(Stopped);
        }
    }
    Ok(())
}
