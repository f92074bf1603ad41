//! Never a failed layout on valid data (issue 12): once a level is chosen,
//! every diagram with a cell left empty (huge weight ratios, identical
//! projections, chains of tiny cells beside huge ones) is repaired locally,
//! in this order, and the repair counted in the [`Report`](crate::layout::Report):
//! 1. the sites with empty cells restart where they provably own a cell
//!    ([`MapSimulation::restart_empty`]) and the areas settle again;
//! 2. else the diagram falls back to its matched-and-swapped start, settled;
//! 3. else to a plain layout of that one diagram (Halton sites, the plain
//!    optimiser), which loses its neighbourhoods but not the picture.
//!
//! Other diagrams are untouched.
//!
//! Before that, [`retarget`] gives every diagram the areas of its real
//! weights: a level is optimised with light children floored at
//! `min_weight_ratio` of their heaviest sibling (room for their neighbours),
//! but a finished diagram must be within the area target of its weights
//! (issue 23 item 6: `/usr/bin` ended 13.5% off while counted converged).

use rayon::prelude::*;

use super::level::{settle, Diagram};
use super::NeighborParams;
use crate::layout::map::{MapSettings, MapSimulation};
use crate::layout::seed;
use crate::layout::treemap::child_targets;
use crate::layout::Params;
use crate::rng::Rng;
use nptreemap_formats::Dataset;

/// What securing a level did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Repairs {
    /// Diagrams mended by restarting their empty cells' sites.
    pub(super) repaired: usize,
    /// Diagrams replaced by their start or a plain layout.
    pub(super) fallbacks: usize,
}

/// Secures every diagram of a finished level; `starts` are the level's
/// diagrams as they were when the optimisation began (same order).
pub(super) fn secure_level(
    diagrams: &mut [Diagram],
    starts: &[Diagram],
    np: &NeighborParams,
    settings: MapSettings,
    seed: u64,
) -> Repairs {
    diagrams
        .par_iter_mut()
        .zip(starts.par_iter())
        .map(|(d, start)| secure(d, start, np, settings, seed))
        .reduce(Repairs::default, |a, b| Repairs {
            repaired: a.repaired + b.repaired,
            fallbacks: a.fallbacks + b.fallbacks,
        })
}

fn secure(
    d: &mut Diagram,
    start: &Diagram,
    np: &NeighborParams,
    settings: MapSettings,
    seed: u64,
) -> Repairs {
    if empty_cells(d) == 0 {
        return Repairs::default();
    }
    if mend(d, np) {
        return Repairs {
            repaired: 1,
            fallbacks: 0,
        };
    }
    let mut fallback = start.clone();
    if !mend(&mut fallback, np) {
        fallback = plain(start, settings, seed);
        mend(&mut fallback, np);
    }
    *d = fallback;
    Repairs {
        repaired: 0,
        fallbacks: 1,
    }
}

/// Sets every diagram's final targets (the floor within its budget,
/// `treemap::floored_targets`) and, where they changed, settles the weights
/// with the sites held; Lloyd ticks finish what settling alone cannot (at
/// most `max_iterations`; a diagram still above its target is counted
/// unconverged in the report).
pub(super) fn retarget(
    diagrams: &mut [Diagram],
    dataset: &Dataset,
    params: &Params,
    np: &NeighborParams,
) {
    diagrams.par_iter_mut().for_each(|d| {
        let Diagram::Sim { children, sim } = d else {
            return;
        };
        let Some(parent) = children.first().and_then(|c| dataset.node(*c).parent) else {
            return;
        };
        let (targets, slack) = child_targets(dataset, parent, sim.clip(), params);
        if slack == sim.slack() && targets.as_slice() == sim.targets() {
            return;
        }
        sim.set_targets(targets);
        sim.set_slack(slack);
        settle(d, np);
        if let Diagram::Sim { sim, .. } = d {
            for _ in 0..sim.settings().max_iterations {
                if sim.converged() {
                    break;
                }
                sim.lloyd_tick();
            }
        }
    });
}

fn empty_cells(d: &Diagram) -> usize {
    match d {
        Diagram::Single { .. } => 0,
        Diagram::Sim { sim, .. } => sim.empty_cells(),
    }
}

/// Restarts the empty cells' sites and settles; true when no cell is empty.
fn mend(d: &mut Diagram, np: &NeighborParams) -> bool {
    for _ in 0..2 {
        if let Diagram::Sim { sim, .. } = d {
            sim.restart_empty();
        }
        settle(d, np);
        if empty_cells(d) == 0 {
            return true;
        }
    }
    false
}

/// A plain layout of the diagram `like`: same parent cell and targets, sites
/// from the Halton start, the plain optimiser (Lloyd and weight steps) to the
/// run's stopping rules.
fn plain(like: &Diagram, settings: MapSettings, seed: u64) -> Diagram {
    let Diagram::Sim { children, sim } = like else {
        return like.clone();
    };
    let clip = sim.clip().clone();
    // Keyed by the first child, as diagrams are keyed by their parent
    // elsewhere: a different stream from the diagram's own.
    let mut rng = Rng::new(seed ^ 0x5eed_fa11_bac4 ^ children[0] as u64);
    let positions = seed::halton_positions(&clip, children.len(), &mut rng);
    let mut plain =
        MapSimulation::new(clip, sim.targets().to_vec(), positions, None, settings, rng);
    plain.set_slack(sim.slack());
    plain.run();
    Diagram::Sim {
        children: children.clone(),
        sim: Box::new(plain),
    }
}
