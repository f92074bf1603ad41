//! nptreemap: neighborhood-preserving Voronoi treemaps.
//!
//! Reduced on branch `wt-power` to the modules this worktree builds: the full
//! module list is restored when the branches are merged.

pub mod geom;
pub mod power;
