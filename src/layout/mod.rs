//! The pure layout optimiser: a validated [`Dataset`] and [`Params`] in, a finished
//! [`Layout`] and a [`Report`] out. No files, no clock, no printing.
//!
//! A layout is computed top-down: the root gets the outline polygon, then each
//! internal node's cell is split among its children by a one-level power-diagram
//! optimisation (`map`), run by the recursion in `treemap` ([`layout()`] is
//! the plain treemap alone; [`compute()`] runs the method the data calls for).
//! A warm layout (`warm`) runs the same recursion from a [`Previous`] layout,
//! given as an explicit argument ([`Request::previous`]), never kept as hidden
//! state.

/// The whole pure layout step: prepare, constraints, method dispatch.
pub mod compute;
/// Which layout strategy runs.
pub mod method;
/// Run parameters and their defaults.
pub mod params;
/// The previous layout of a dataset, keyed by node id: a warm start's input.
pub mod previous;
/// Progress reports and the stop they can ask for.
pub mod progress;
/// Items of weight 0: hidden before the layout, or drawn at the floor.
pub mod zero;

// The stages of the optimiser: crate-private (see `internal!` in lib.rs); what
// the API needs of them is re-exported below.
internal! {
    /// Invariant checks a finished layout must pass.
    mod check;
    /// Snapshots of a similarity layout during optimisation, for the HTML slider.
    mod frames;
    /// One-level optimiser: Lloyd steps plus weight adaptation towards target areas.
    mod map;
    /// Similarity-driven layouts: initialisation, baselines, joint optimisation.
    mod similar;
    /// Start positions and weights for one diagram.
    mod seed;
    /// Top-down recursion over the hierarchy.
    mod treemap;
    /// The warm layout: start every diagram from the previous layout, settle areas.
    mod warm;
}

use crate::geom::shared_edge::extent_diagonal;
use crate::geom::{level_adjacency, ConvexPolygon, LevelAdjacency, Point};
use nptreemap_formats::Dataset;

pub use check::SanityError;
pub use compute::{compute, Computed, LayoutSettings, Request, Start};
pub use frames::Frame;
pub use method::Method;
pub use params::{Canvas, Outline, Params};
pub use previous::{Previous, PreviousNode, WarmRefusal};
pub use progress::{Progress, ProgressFn, ProgressSink};
pub use similar::NeighborParams;
pub use treemap::layout;
pub use zero::{ZeroItems, ZeroWeights};

/// The finished geometry of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutCell {
    /// The power-diagram site that produced this cell (for the root: the outline centroid).
    pub site: Point,
    /// The site's power weight at the end of the optimisation (0 for the root and
    /// for only children, which take their parent's cell).
    pub power_weight: f64,
    /// The cell: convex, inside the parent's cell.
    pub polygon: ConvexPolygon,
}

#[cfg(test)]
impl LayoutCell {
    /// The cell of an axis-aligned rectangle, its site the centroid (test
    /// fixtures of hand-made layouts).
    pub(crate) fn rectangle(x: f64, y: f64, w: f64, h: f64) -> LayoutCell {
        let polygon = ConvexPolygon::rectangle(x, y, w, h).expect("positive rectangle");
        LayoutCell {
            site: polygon.centroid(),
            power_weight: 0.0,
            polygon,
        }
    }
}

/// A finished layout: one cell per dataset node, indexed like [`Dataset::nodes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The drawing surface the layout was made for.
    pub canvas: Canvas,
    /// One cell per node, in the dataset's node order.
    pub cells: Vec<LayoutCell>,
}

/// Figures about how a layout run went. Not converging is reported here, not an error.
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct Report {
    /// Diagrams optimised (internal nodes with two or more children).
    pub diagrams: usize,
    /// Optimiser ticks summed over all diagrams.
    pub iterations: usize,
    /// Mean over diagrams of Σ|A − A*| / A(parent) (d3-voronoi-map's `convergenceRatio`).
    pub area_error_mean: f64,
    /// Largest per-diagram area error.
    pub area_error_max: f64,
    /// Diagrams that stopped at `max_iterations` above the convergence target.
    pub unconverged: usize,
    /// Diagrams whose start already met the area target, so no tick ran: with
    /// a warm start, diagrams taken over unchanged from the previous layout
    /// (always 0 for a cold layout, whose diagrams make at least one tick).
    pub reused: usize,
    /// Cells the optimiser left empty and that got a stand-in sliver; 0 unless
    /// the input is pathological. Such a layout fails `sanity_check`.
    pub degenerate: usize,
    /// Diagrams of a similarity layout in which cells had emptied and were
    /// mended by restarting their sites (issue 12: repaired, never an error).
    pub repaired: usize,
    /// Diagrams of a similarity layout that could not be mended and fell back
    /// to their matched-and-swapped start, or to a plain layout of that one
    /// diagram.
    pub fallbacks: usize,
    /// Snapshots of the optimisation, level by level, when asked for
    /// ([`NeighborParams::frames`]); empty otherwise.
    pub frames: Vec<Frame>,
}

impl Report {
    /// Counts one optimised diagram: its ticks, its area error (the caller
    /// sums the errors for [`Report::set_mean`]) and whether it converged.
    /// The one place both engines count a diagram, so their reports agree.
    pub(crate) fn count_diagram(&mut self, iterations: usize, error: f64, converged: bool) {
        self.diagrams += 1;
        self.iterations += iterations;
        self.area_error_max = self.area_error_max.max(error);
        if !converged {
            self.unconverged += 1;
        }
    }

    /// Sets the mean area error from the sum of the counted diagrams' errors.
    pub(crate) fn set_mean(&mut self, error_sum: f64) {
        if self.diagrams > 0 {
            self.area_error_mean = error_sum / self.diagrams as f64;
        }
    }

    /// This report and `below`'s (a deeper level's) as one; the mean is left
    /// for [`Report::set_mean`] once every level is in.
    pub(crate) fn merge(self, below: Report) -> Report {
        Report {
            diagrams: self.diagrams + below.diagrams,
            iterations: self.iterations + below.iterations,
            area_error_mean: 0.0,
            area_error_max: self.area_error_max.max(below.area_error_max),
            unconverged: self.unconverged + below.unconverged,
            reused: self.reused + below.reused,
            degenerate: self.degenerate + below.degenerate,
            repaired: self.repaired + below.repaired,
            fallbacks: self.fallbacks + below.fallbacks,
            frames: self.frames.into_iter().chain(below.frames).collect(),
        }
    }
}

impl Layout {
    /// The cell of node `index`.
    pub fn cell(&self, index: usize) -> &LayoutCell {
        &self.cells[index]
    }

    /// The layout's length scale for shared-edge tolerances: the diagonal of
    /// the bounding box of every cell, as the layout checker computes it from
    /// the polygons (for a rectangle outline, the canvas diagonal); the canvas
    /// diagonal when there are no cells, 1 when that is degenerate too.
    pub fn diagonal(&self) -> f64 {
        let diag = extent_diagonal(self.cells.iter().map(|c| &c.polygon))
            .unwrap_or_else(|| Point::new(self.canvas.width, self.canvas.height).length());
        if diag > 0.0 && diag.is_finite() {
            diag
        } else {
            1.0
        }
    }

    /// Which cells among `nodes` (one depth level, node indices) share an edge.
    pub fn level_adjacency(&self, nodes: &[usize]) -> LevelAdjacency {
        level_adjacency(
            |i| self.cells.get(i).map(|c| &c.polygon),
            nodes,
            self.diagonal(),
        )
    }

    /// Checks every invariant of a finished layout against its dataset; see `layout::check`.
    pub fn sanity_check(&self, dataset: &Dataset) -> Result<(), SanityError> {
        check::sanity_check(self, dataset)
    }
}

/// Errors a layout run can return. Bad data never reaches here (the dataset is
/// validated when built), and valid data always gets a layout (cells that
/// empty are repaired, see [`Report::repaired`]); these are about parameters,
/// or a stop the caller asked for.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum LayoutError {
    /// A parameter is out of its range.
    #[error("invalid layout parameter `{name}`: {reason}")]
    InvalidParam {
        /// The parameter's name as in the config file.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A similarity-driven method was asked for data without a similarity.
    #[error(
        "method `{method}` needs a similarity, and the data has none (give one with --similarity)"
    )]
    NoSimilarity {
        /// The method asked for.
        method: &'static str,
    },
    /// The progress callback asked the run to stop
    /// ([`Request::progress`](compute::Request::progress)).
    #[error("the layout was cancelled")]
    Cancelled,
}
