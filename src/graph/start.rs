//! Warm or cold: the one place a build decides which previous layout its
//! layout starts from. In order:
//!
//! For `layout`, `eval` and `bench`, which build no configured dataset, the
//! previous layout is the `--previous` file, unless `--cold` ([`given`]).
//! For `build` and `watch` ([`choose`]), in order:
//!
//! 1. `--cold` (or caching turned off, `NPTREEMAP_NO_CACHE`): none.
//! 2. The graph's own last layout, kept in memory between rebuilds (the
//!    watch daemon), if it was made with the layout settings in force.
//! 3. The stored layout (`crate::state::layout`), if it records that it was
//!    made with the layout settings in force.
//! 4. Otherwise none, and the build says why: nothing stored yet, the
//!    layout settings changed (seed, method, outline, canvas, similarity,
//!    convergence, iterations: every setting that shapes the picture), or
//!    the stored layout has no record of its settings (an older version made
//!    it).
//!
//! The layout core then checks that the previous layout fits the data
//! (`Previous::fits`: at least half the nodes survive); one that does not
//! is refused and the layout starts cold, as it says.

use std::sync::Arc;

use crate::config::DatasetConfig;
use crate::fingerprint::Fingerprint;
use crate::layout::{Computed, Previous};
use crate::state;

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

/// The graph's last layout and the settings it was made with.
pub struct Memory<'a> {
    /// Its settings' fingerprint.
    pub settings: Fingerprint,
    /// The layout.
    pub computed: &'a Computed,
}

/// The previous layout of a run given one on the command line
/// (`--previous`): it, unless `cold` (`--cold`).
pub fn given(previous: Option<Arc<Previous>>, cold: bool) -> Option<Arc<Previous>> {
    if cold {
        None
    } else {
        previous
    }
}

/// Chooses the previous layout of a run with layout settings `settings`
/// (see the module doc for the order); `cold` says why none may be used
/// (`--cold`), if so.
pub fn choose(
    d: &DatasetConfig,
    cold: Option<&'static str>,
    memory: Option<Memory<'_>>,
    settings: Fingerprint,
) -> Chosen {
    let cold_because = |why| Chosen {
        cold_because: Some(why),
        ..Chosen::default()
    };
    if let Some(why) = cold {
        return cold_because(why);
    }
    if let Some(memory) = memory {
        if memory.settings != settings {
            return cold_because("the layout settings changed");
        }
        return Chosen {
            previous: Some(Arc::new(memory.computed.previous())),
            ..Chosen::default()
        };
    }
    let stored = state::layout::read(d);
    if let Some(warning) = stored.warning {
        return Chosen {
            cold_because: Some("the stored layout cannot be read"),
            warning: Some(warning),
            ..Chosen::default()
        };
    }
    let (Some(previous), Some(bytes)) = (stored.previous, stored.fingerprint) else {
        return cold_because("no stored layout");
    };
    match stored.settings {
        Some(made_with) if made_with == settings => Chosen {
            previous: Some(previous),
            // Left by an older version elsewhere: not where it is kept now,
            // so the commit writes it there.
            stored: (!stored.older).then_some(bytes),
            ..Chosen::default()
        },
        Some(_) => cold_because("the layout settings changed since the stored layout"),
        None => cold_because("the stored layout has no record of its layout settings"),
    }
}
