//! Where a build starts: the one place that decides whether anything needs
//! doing at all, and which previous layout a layout starts from. Every
//! command and the daemon go through [`decide`] (or, for `layout`, `eval`
//! and `bench`, which build no configured dataset, [`given`]); its reason is
//! in the layout stage's `-v` line. In order:
//!
//! 1. `--cold` (or caching turned off, `NPTREEMAP_NO_CACHE`): a cold layout,
//!    nothing reused.
//! 2. Nothing changed: the manifest records the same inputs and layout
//!    settings, and every output's file holds what they render (the style
//!    and the page's history included in each output's key): nothing runs.
//!    The daemon's "an event that changed nothing says nothing" is this.
//! 3. The graph's own last layout, kept in memory between rebuilds (the
//!    watch daemon): taken over when made from the same inputs and settings,
//!    else the warm start when made with the same settings.
//! 4. The stored layout (`crate::state::layout`), if it records that it was
//!    made with the layout settings in force.
//! 5. Otherwise cold, and the build says why: nothing stored yet, the
//!    layout settings changed (seed, method, outline, canvas, similarity,
//!    convergence, iterations: every setting that shapes the picture), or
//!    the stored layout has no record of its settings (an older version made
//!    it).
//!
//! The layout core then checks that the previous layout fits the data
//! (`Previous::fits`: at least half the nodes survive, the same canvas);
//! one that does not is refused there, since only the core knows the nodes
//! that survive, and the build says so.

use std::sync::Arc;

use crate::fingerprint::Fingerprint;
use crate::layout::{Computed, Previous};
use crate::state::layout::StoredLayout;

/// The previous layout chosen for a run, and why.
#[derive(Debug, Default)]
pub struct Chosen {
    /// The layout to start from; `None` for a cold start.
    pub previous: Option<Arc<Previous>>,
    /// The fingerprint of the stored layout's bytes, when it was chosen.
    pub stored: Option<Fingerprint>,
    /// Why the start is cold, in a few words (`None` when warm).
    pub cold_because: Option<&'static str>,
    /// A stored layout that is there but cannot be read: the user is told,
    /// since the picture will move.
    pub warning: Option<String>,
}

/// The graph's last layout and what it was made from.
#[derive(Clone, Copy)]
pub struct Memory<'a> {
    /// Its inputs' fingerprint.
    pub inputs: Fingerprint,
    /// Its settings' fingerprint.
    pub settings: Fingerprint,
    /// The layout.
    pub computed: &'a Computed,
    /// Its previous-layout form, when made ahead (`DatasetGraph::ready_next`).
    pub previous: Option<&'a Arc<Previous>>,
}

/// What [`decide`] decides from.
#[derive(Clone, Copy)]
pub struct Facts<'a> {
    /// Why nothing may be reused, if so ([`refusal`]).
    pub refusal: Option<&'static str>,
    /// The fingerprint of the inputs as read now.
    pub inputs: Fingerprint,
    /// The fingerprint of the layout settings in force.
    pub settings: Fingerprint,
    /// Whether the outputs on disk are what these inputs, settings and style
    /// make (the manifest vouches for each file's bytes).
    pub outputs_current: bool,
    /// The graph's last layout, if it has one.
    pub memory: Option<Memory<'a>>,
}

/// Where a build starts.
#[derive(Debug)]
pub enum Decision {
    /// Nothing changed: nothing runs.
    UpToDate,
    /// The layout in memory was made from the same inputs and settings: it
    /// is the layout, and only what it feeds runs.
    Same,
    /// Lay out, from the previous layout chosen (or cold, with why).
    LayOut(Chosen),
}

/// Why a build may not reuse anything, if it may not: `--cold`, or caching
/// turned off.
pub fn refusal(cold: bool, cache: bool) -> Option<&'static str> {
    if cold {
        Some("--cold")
    } else if !cache {
        Some("caching off: NPTREEMAP_NO_CACHE")
    } else {
        None
    }
}

/// The decision (see the module doc for the order). `stored` reads the
/// stored layout; it is called only when the decision needs it.
pub fn decide(facts: Facts<'_>, stored: impl FnOnce() -> StoredLayout) -> Decision {
    let cold = |why| {
        Decision::LayOut(Chosen {
            cold_because: Some(why),
            ..Chosen::default()
        })
    };
    if let Some(why) = facts.refusal {
        return cold(why);
    }
    if facts.outputs_current {
        return Decision::UpToDate;
    }
    if let Some(memory) = facts.memory {
        if memory.settings != facts.settings {
            return cold("the layout settings changed");
        }
        if memory.inputs == facts.inputs {
            return Decision::Same;
        }
        return Decision::LayOut(Chosen {
            previous: Some(
                memory
                    .previous
                    .map_or_else(|| memory.computed.previous(), Arc::clone),
            ),
            ..Chosen::default()
        });
    }
    let stored = stored();
    if let Some(warning) = stored.warning {
        return Decision::LayOut(Chosen {
            cold_because: Some("the stored layout cannot be read"),
            warning: Some(warning),
            ..Chosen::default()
        });
    }
    let (Some(previous), Some(bytes)) = (stored.previous, stored.fingerprint) else {
        return cold("no stored layout");
    };
    match stored.settings {
        Some(made_with) if made_with == facts.settings => Decision::LayOut(Chosen {
            previous: Some(previous),
            // Left by an older version elsewhere: not where it is kept now,
            // so the commit writes it there.
            stored: (!stored.older).then_some(bytes),
            ..Chosen::default()
        }),
        Some(_) => cold("the layout settings changed since the stored layout"),
        None => cold("the stored layout has no record of its layout settings"),
    }
}

/// The previous layout of a run given one on the command line
/// (`--previous`): what `previous` gives (reading it only then), unless
/// `cold` (`--cold`).
pub fn given<T>(cold: bool, previous: impl FnOnce() -> T) -> Option<T> {
    (!cold).then(previous)
}
