//! `Params`: everything a layout run depends on besides the dataset, with the
//! defaults in one place. Names follow d3-voronoi-map where the concept is the same
//! (`convergence_ratio`, `max_iterations`, `min_weight_ratio`).

use super::zero::ZeroWeights;
use super::LayoutError;
use crate::geom::{ConvexPolygon, Point};

/// The drawing surface, in output units (pixels for SVG).
#[derive(serde::Serialize, Clone, Copy, Debug, PartialEq)]
pub struct Canvas {
    /// Width. Default: 1000.
    pub width: f64,
    /// Height. Default: 1000.
    pub height: f64,
}

impl Default for Canvas {
    fn default() -> Self {
        Self {
            width: 1000.0,
            height: 1000.0,
        }
    }
}

/// The shape of the root cell. Named in configs (`layout.outline`) and on the
/// command line (`--outline`) as `rect`, `circle` or `ngon`.
#[derive(serde::Serialize, Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(try_from = "String")]
#[non_exhaustive]
pub enum Outline {
    /// The whole canvas (the default).
    Rectangle,
    /// The largest circle centred on the canvas, as a regular 128-gon (cells are
    /// polygons; 128 sides keep the outline smooth at any print size).
    Circle,
    /// The largest regular polygon with this many sides centred on the canvas,
    /// one vertex at the top (the paper's prototype uses a 32-gon).
    Regular(usize),
    /// Any convex polygon in canvas coordinates.
    Custom(ConvexPolygon),
}

/// Vertices used to approximate a circular outline.
const CIRCLE_SIDES: usize = 128;

/// Sides of the `ngon` outline: the paper prototype's 32-gon.
const NGON_SIDES: usize = 32;

/// An outline name that is not `rect`, `circle` or `ngon`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown outline {0:?} (expected rect, circle or ngon)")]
pub struct OutlineNameError(String);

impl std::str::FromStr for Outline {
    type Err = OutlineNameError;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        match name {
            "rect" => Ok(Outline::Rectangle),
            "circle" => Ok(Outline::Circle),
            "ngon" => Ok(Outline::Regular(NGON_SIDES)),
            other => Err(OutlineNameError(other.to_string())),
        }
    }
}

impl TryFrom<String> for Outline {
    type Error = OutlineNameError;

    fn try_from(name: String) -> Result<Self, Self::Error> {
        name.parse()
    }
}

impl Outline {
    /// The root polygon on `canvas`.
    pub fn polygon(&self, canvas: Canvas) -> Result<ConvexPolygon, LayoutError> {
        let center = Point::new(canvas.width / 2.0, canvas.height / 2.0);
        let radius = canvas.width.min(canvas.height) / 2.0;
        let built = match self {
            Outline::Rectangle => ConvexPolygon::rectangle(0.0, 0.0, canvas.width, canvas.height),
            Outline::Circle => ConvexPolygon::regular(center, radius, CIRCLE_SIDES),
            Outline::Regular(sides) => ConvexPolygon::regular(center, radius, *sides),
            Outline::Custom(p) => Ok(p.clone()),
        };
        built.map_err(|e| LayoutError::InvalidParam {
            name: "outline",
            reason: e.to_string(),
        })
    }
}

/// The smallest canvas side. The geometry's tolerances are absolute at the
/// scale of a unit (the checker's shared-edge length among them), so below 1
/// cells stop sharing edges and areas stop converging (a 0.01 canvas fails
/// the checker; 1e-100 ran for minutes).
pub const CANVAS_MIN: f64 = 1.0;

/// The largest canvas side: a million output units (pixels) is past any
/// screen or print; far beyond it the projections' constants lose precision
/// (1e100 panicked in the neighbourhood optimiser). Tested up to 1e10.
pub const CANVAS_MAX: f64 = 1_000_000.0;

/// Parameters of a layout run.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Params {
    /// Drawing surface. Default: 1000 × 1000.
    pub canvas: Canvas,
    /// Root outline. Default: [`Outline::Rectangle`].
    pub outline: Outline,
    /// Seed for every random choice; the same seed gives the same layout. Default: 1.
    pub seed: u64,
    /// A diagram has converged when Σ|A − A*| / A(parent) falls below this
    /// (d3-voronoi-map's `convergenceRatio`, same default). Default: 0.01.
    pub convergence_ratio: f64,
    /// Ticks after which a diagram stops even if not converged; reported, not an
    /// error. Default: 200.
    pub max_iterations: usize,
    /// Ticks every diagram makes before it may stop: Lloyd relaxation that gives
    /// cells round shapes even when the areas converge sooner. Default: 8.
    pub min_iterations: usize,
    /// Siblings lighter than this share of the heaviest sibling are laid out as if
    /// they had that share, so zero-weight leaves still get a visible cell
    /// (d3-voronoi-map's `minWeightRatio`; d3 uses 0.01, we keep areas exact
    /// down to 1:1000). Default: 0.001.
    pub min_weight_ratio: f64,
    /// What becomes of items of weight 0: no cell, or a cell at the floor of
    /// `min_weight_ratio` ([`ZeroWeights`], applied before the layout by
    /// [`zero::apply`](super::zero::apply)). Default: hide.
    pub zero_weights: ZeroWeights,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            canvas: Canvas::default(),
            outline: Outline::Rectangle,
            seed: 1,
            convergence_ratio: 0.01,
            max_iterations: 200,
            min_iterations: 8,
            min_weight_ratio: 0.001,
            zero_weights: ZeroWeights::Hide,
        }
    }
}

impl Params {
    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), LayoutError> {
        let bad = |name, reason: &str| {
            Err(LayoutError::InvalidParam {
                name,
                reason: reason.to_string(),
            })
        };
        let c = self.canvas;
        let range = format!("must be a number from {CANVAS_MIN} to {CANVAS_MAX}");
        if !(CANVAS_MIN..=CANVAS_MAX).contains(&c.width) {
            return bad("width", &range);
        }
        if !(CANVAS_MIN..=CANVAS_MAX).contains(&c.height) {
            return bad("height", &range);
        }
        if !(self.convergence_ratio.is_finite() && self.convergence_ratio >= 0.0) {
            return bad("convergence_ratio", "must be a number >= 0");
        }
        if !(0.0..1.0).contains(&self.min_weight_ratio) {
            return bad("min_weight_ratio", "must be in [0, 1)");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1");
        }
        Ok(())
    }
}
