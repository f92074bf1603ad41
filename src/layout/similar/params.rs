//! The settings of the similarity-driven methods ([`NeighborParams`]) and the
//! distance rules of one level's attraction moves ([`Distances`]), with the
//! constants behind them and where each comes from.

/// Settings of the similarity-driven methods.
#[derive(serde::Serialize, Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct NeighborParams {
    /// Lloyd ticks of the equal-area CVT every diagram starts from. Default: 40.
    pub cvt_iterations: usize,
    /// Most ticks of the joint optimisation per level (the prototype's 150).
    /// A level usually stops earlier, when its score has plateaued
    /// ([`NeighborParams::patience`]). Default: 150.
    pub ticks: usize,
    /// A level's optimisation stops once this many ticks in a row have not
    /// raised its best score by a meaningful step (half a constraint, or 0.2%
    /// on large levels); 0 runs all `ticks`. Default: 30.
    pub patience: usize,
    /// Greedy swap rounds after matching (method-reference §4.4). Default: 4.
    pub swap_rounds: usize,
    /// One more swap round every this many ticks, until 20 ticks before the end
    /// (the prototype's t = 20, 40, …, 120). 0 disables. Default: 20.
    pub swap_every: usize,
    /// Weight-only ticks at most to settle the areas at the end. Default: 100.
    pub settle_iterations: usize,
    /// Cell-starts per level to spend on independent starts of `neighbor`
    /// (small levels get several, large ones one). Default: 200.
    pub start_budget: usize,
    /// Most independent starts per level. Default: 8.
    pub max_starts: usize,
    /// Hierarchies with at most this many nodes (after preparation) choose
    /// among each level's best candidates by laying out everything below them.
    /// Default: 64.
    pub lookahead_max_nodes: usize,
    /// What shape costs in a level's score: each cell's bounding-box aspect
    /// ratio above 1 counts this many constraints against it (issue 12: long
    /// cells cannot hold a label). Default: 0.25.
    pub shape_weight: f64,
    /// Share of the way to its cell's centroid every site goes each tick,
    /// besides its attraction move: the pull that keeps cells round. 0 turns
    /// it off. Default: 0.1.
    pub centroid_pull: f64,
    /// Run the paper prototype's optimiser instead of ours (method-reference
    /// §5): 151 ticks, weights held at the CVT's until t = 105 and then grown
    /// by d3's ±10% steps, a 0.8 Lloyd step for cells without an attraction
    /// move, pure Lloyd in the last 10 ticks, the prototype's pixel constants
    /// scaled to the canvas, one start. Areas are not settled afterwards, so the
    /// area error is the prototype's too. Default: false.
    pub prototype: bool,
    /// Frames per level recorded while optimising, for the HTML page's
    /// slider (see [`crate::layout::Frame`]); 0 records none. Recording does not
    /// change the layout. Default: 0.
    pub frames: usize,
}

impl Default for NeighborParams {
    fn default() -> Self {
        Self {
            cvt_iterations: 40,
            ticks: 150,
            patience: 30,
            swap_rounds: 4,
            swap_every: 20,
            settle_iterations: 100,
            start_budget: 200,
            max_starts: 8,
            lookahead_max_nodes: 64,
            shape_weight: SHAPE_WEIGHT,
            centroid_pull: CENTROID_PULL,
            prototype: false,
            frames: 0,
        }
    }
}

/// Default [`NeighborParams::shape_weight`]: a quarter of a constraint per
/// unit of aspect above 1 (issue 12: long cells cannot hold a label). What
/// other values trade, constraints realised against leaf aspect, is the
/// table of `examples/pareto.rs` in BENCHMARKS.md.
pub(crate) const SHAPE_WEIGHT: f64 = 0.25;

/// Default [`NeighborParams::centroid_pull`]; see [`SHAPE_WEIGHT`].
pub(crate) const CENTROID_PULL: f64 = 0.1;

/// Distance constants as shares of the level's unit length, the square root of
/// its mean cell area. Derived from the prototype's pixels (method-reference
/// §5.6–5.7) on its country map, where leaf cells average about 4,000 px², a
/// unit of 63 px: `D_OPT` 40 px, `D_MAX` 80 px, step 5 px × 0.8, gap 10 px.
const D_OPT: f64 = 0.63;
const D_MAX: f64 = 1.27;
const STEP: f64 = 0.063;
const GAP: f64 = 0.16;
/// Share of the way to the centroid a Lloyd step goes (the prototype's 0.8, §5.7c).
const CENTROID_STEP: f64 = 0.8;
/// Farthest an attraction move may take a site from its cell's centroid, in
/// units of the cell's own size (square root of its target area), unless the
/// move brings it closer: an attraction move is judged by what it does to the
/// cell's shape as well as to its neighbourhoods (issue 12). A power cell
/// whose site sits far off its centroid is long.
const MAX_OFFSET: f64 = 0.35;

/// The distance rules of one level's attraction moves (method-reference
/// §5.6–5.7).
#[derive(Clone, Copy, Debug)]
pub(super) struct Distances {
    /// Below this, attraction towards a partner stops (`distance_min`).
    pub(super) d_opt: f64,
    /// Below this, neighbouring cousins slide along the parent edge (`distance_max`).
    pub(super) d_max: f64,
    /// Length of one attraction move.
    pub(super) step: f64,
    /// Closest a moved site may come to another site or the parent's boundary.
    pub(super) gap: f64,
    /// Share of the way to the centroid a cell without an attraction move goes
    /// (the prototype's Lloyd step); 0 for none.
    pub(super) idle_step: f64,
    /// Share of the way to the centroid every site goes after its move.
    pub(super) pull: f64,
    /// Farthest a move may take a site from its centroid, per unit of the
    /// cell's size; infinite for no limit.
    pub(super) max_offset: f64,
}

/// Area of the prototype's root, a regular 32-gon of circumradius 192 px, the
/// size its pixel constants were tuned for (method-reference §10 row 1).
pub(super) fn prototype_root_area() -> f64 {
    0.5 * 32.0 * (std::f64::consts::TAU / 32.0).sin() * 192.0 * 192.0
}

impl Distances {
    /// Ours: shares of the level's unit length (see `D_OPT`), with the
    /// centroid pull of `np`.
    pub(super) fn relative(unit: f64, np: &NeighborParams) -> Self {
        let pull = np.centroid_pull.clamp(0.0, 1.0);
        Self {
            d_opt: D_OPT * unit,
            d_max: D_MAX * unit,
            step: STEP * unit,
            gap: GAP * unit,
            // The prototype's 0.8 Lloyd step for idle cells undid more
            // neighbourhoods than it helped shapes (flare 189 → 240 realised
            // at seed 1 without it); the gentler pull on every cell replaces it.
            idle_step: 0.0,
            pull,
            max_offset: if pull > 0.0 {
                MAX_OFFSET
            } else {
                f64::INFINITY
            },
        }
    }

    /// The prototype's pixels (40, 80, 5 × 0.8, 10 or 15 below depth 2), scaled
    /// by `scale` = the root's size against the prototype's 32-gon of radius 192.
    pub(super) fn prototype(scale: f64, depth: usize) -> Self {
        Self {
            d_opt: 40.0 * scale,
            d_max: 80.0 * scale,
            step: 4.0 * scale,
            gap: if depth > 2 { 15.0 } else { 10.0 } * scale,
            idle_step: CENTROID_STEP,
            pull: 0.0,
            max_offset: f64::INFINITY,
        }
    }
}
