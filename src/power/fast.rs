//! The fast path, [`power_diagram`]: each cell is built by clipping the clip
//! polygon with the bisectors of nearby sites, found through [`Grid`], until the
//! security radius proves no other site can cut. Owns the visiting order and the
//! parallel loop; may not change the clipping kernel or the output assembly.

use rayon::prelude::*;

use super::assemble::{cannot_cut, empty_cell, symmetrize, CellBuilder, Prepared};
use super::clip::LabeledPolygon;
use super::grid::Grid;
use super::{Cell, PowerDiagram, Site};
use crate::geom::{ConvexPolygon, Point};

/// From this many sites on, cells are built in parallel. Below it the thread
/// hand-off costs more than it saves.
const PARALLEL_FROM: usize = 512;

/// The first candidates (the 3 × 3 buckets around the site) are sorted by
/// distance so the cell shrinks fast; a block holding more than this many
/// sites (heavily clustered or coincident input) is taken in index order
/// instead, which is just as correct and avoids sorting a huge block once per
/// site.
const SORT_AT_MOST: usize = 64;

/// Outermost ring of buckets (Chebyshev radius) searched around the site
/// before falling back to the pyramid: rings 2 and 3, beyond the first 3 × 3
/// block, settle about 97% of the cells of evenly spread sites (counted once with
/// temporary counters on the `examples/power_speed` inputs); more rings would only repeat what the pyramid does
/// better.
const RINGS: usize = 3;

/// Whether all leaf buckets under node `(x, y)` of level `lvl` lie within
/// Chebyshev distance `r` of leaf bucket `(bx, by)`.
fn within_block(x: usize, y: usize, lvl: usize, bx: usize, by: usize, r: usize) -> bool {
    let span = |c: usize, center: usize| {
        let first = c << lvl;
        let last = ((c + 1) << lvl) - 1;
        first >= center.saturating_sub(r) && last <= center + r
    };
    span(x, bx) && span(y, by)
}

/// The power diagram of `sites` clipped to `clip`, computed cell by cell with a
/// security-radius stop (near O(n log n) on spread-out sites).
///
/// Sites with a NaN or infinite coordinate or weight are ignored: their cell is
/// empty (`polygon: None`, `dominated_by: None`, centroid = their position) and
/// they do not affect other cells. Sites outside `clip` are allowed. Coincident
/// sites: the higher weight takes the whole shared region; on equal weights the
/// lower index does, and the other is reported as dominated by it.
///
/// The result is bit-identical whether or not it is computed in parallel.
pub fn power_diagram(sites: &[Site], clip: &ConvexPolygon) -> PowerDiagram {
    power_diagram_with(sites, clip, sites.len() >= PARALLEL_FROM)
}

/// [`power_diagram`] with the choice of parallelism made by the caller (tests
/// use it to show both ways give identical bits).
pub(crate) fn power_diagram_with(
    sites: &[Site],
    clip: &ConvexPolygon,
    parallel: bool,
) -> PowerDiagram {
    let input = Prepared::new(sites, clip);
    let (lo, hi) = clip.bbox();
    let grid = Grid::new(&input.pos, &input.w, &input.active, lo, hi);
    let n = input.len();
    // Cells are built in the grid's spatial order, so neighbouring sites' data
    // is still in cache, then put back in site order; each cell depends only
    // on the input, so order and threading cannot change a bit of the result.
    let order = grid.spatial_order();
    let build = |state: &mut Walker, i: &usize| -> Cell { state.cell(&input, &grid, *i) };
    let built: Vec<Cell> = if parallel {
        order.par_iter().map_init(Walker::new, build).collect()
    } else {
        let mut state = Walker::new();
        order.iter().map(|i| build(&mut state, i)).collect()
    };
    // Sites outside the grid (ignored or shadowed) get their empty cells here.
    let mut cells: Vec<Cell> = (0..n)
        .map(|i| empty_cell(input.pos[i], input.shadow[i]))
        .collect();
    for (&i, cell) in order.iter().zip(built) {
        cells[i] = cell;
    }
    symmetrize(&mut cells, parallel);
    PowerDiagram { cells }
}

/// Per-thread scratch for building cells; its contents never influence results.
struct Walker {
    builder: CellBuilder,
    /// (squared distance, index, position, weight) of the first sites to visit.
    candidates: Vec<(f64, usize, Point, f64)>,
    /// Pending pyramid nodes: (squared distance lower bound, level, node).
    stack: Vec<(f64, usize, usize)>,
}

impl Walker {
    fn new() -> Self {
        Walker {
            builder: CellBuilder::new(LabeledPolygon::default()),
            candidates: Vec::new(),
            stack: Vec::new(),
        }
    }

    /// Whether a pyramid node with squared distance `d2` from the site and
    /// largest weight `wmax` can be skipped. While the cell has area: when no
    /// site in it can cut (see [`cannot_cut`], which also rules out
    /// dominators). Once the cell is empty only the nearest dominator is still
    /// sought: a dominator `j` has `w_j − w_i ≥ d_j² ≥ d2` and must be no
    /// farther than the best one found so far.
    fn prune(&self, d2: f64, wmax: f64) -> bool {
        let b = &self.builder;
        if b.poly.is_empty() {
            d2 > wmax - b.weight() || b.best.is_some_and(|(bd2, _)| d2 > bd2)
        } else {
            cannot_cut(d2, wmax, b.poly.r2, b.weight())
        }
    }

    /// Visits every site of a leaf bucket outside the first block (so never
    /// the site itself).
    fn visit_bucket(&mut self, grid: &Grid, x: usize, y: usize) {
        let b = grid.bucket(x, y);
        for (n, &j) in b.index.iter().enumerate() {
            self.builder.visit(j, b.pos[n], b.w[n], true);
        }
    }

    /// [`Self::prune`] for a box of sites, sharpened: when the circle bound
    /// alone is not enough, the test is made at each vertex `v` of the cell.
    /// If `dist(v, box)² − wmax ≥ |v − p_i|² − w_i` at every vertex, then for
    /// each site `j` in the box `|v − p_j|² − w_j ≥ |v − p_i|² − w_i` at every
    /// vertex; that difference is affine in `v`, so it holds on the whole
    /// convex cell and `j` cannot cut it. This settles long thin cells (sites
    /// on a line, elongated treemap cells), whose circumscribed circle is far
    /// larger than the cell. `dist2` gives the squared distance from a point
    /// (absolute coordinates) to the box.
    fn prune_box(&self, d2: f64, wmax: f64, dist2: impl Fn(Point) -> f64) -> bool {
        if self.prune(d2, wmax) {
            return true;
        }
        let b = &self.builder;
        if b.poly.is_empty() {
            return false;
        }
        let (p, wi) = (b.position(), b.weight());
        // The site itself is tested like a vertex (`d2` is its distance to the
        // box): the argument then covers the hull of the cell and the site, so
        // the box holds no dominator either even when the site lies outside its
        // cell, and `dominated_by` stays exact.
        d2 - wmax >= -wi
            && b.poly
                .verts
                .iter()
                .all(|v| dist2(*v + p) - wmax >= v.length_squared() - wi)
    }

    fn cell(&mut self, input: &Prepared<'_>, grid: &Grid, i: usize) -> Cell {
        self.builder.start(input, i);
        let p = self.builder.position();
        let (bx, by) = grid.bucket_xy(p);
        let leaf = &grid.levels[0];

        // Nearest candidates first: the 3 × 3 block of buckets around the site.
        self.candidates.clear();
        for y in by.saturating_sub(1)..(by + 2).min(leaf.ny) {
            for x in bx.saturating_sub(1)..(bx + 2).min(leaf.nx) {
                let b = grid.bucket(x, y);
                for (n, &j) in b.index.iter().enumerate() {
                    if j != i {
                        let d2 = (b.pos[n] - p).length_squared();
                        self.candidates.push((d2, j, b.pos[n], b.w[n]));
                    }
                }
            }
        }
        if self.candidates.len() <= SORT_AT_MOST {
            self.candidates
                .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        for &(_, j, pj, wj) in &self.candidates {
            self.builder.visit(j, pj, wj, true);
        }

        // Then a few rings of buckets around the block: on evenly spread sites
        // the security radius is met within them. Every site in ring `r` or
        // beyond is at least `ring_bound(r)` away and no heavier than the global
        // maximum weight, so once `prune` holds for that pair nothing farther
        // out matters and the cell is final.
        let wmax = grid.max_weight();
        for r in 2..=RINGS {
            let bound = grid.ring_bound(p, bx, by, r);
            let beyond = |v: Point| grid.ring_bound(v, bx, by, r).powi(2);
            if self.prune_box(bound * bound, wmax, beyond) {
                return self.builder.finish(input.clip, input.edge_tol);
            }
            grid.for_ring(bx, by, r, |x, y| {
                let k = y * leaf.nx + x;
                if !self.prune_box(leaf.dist2(k, p), leaf.wmax[k], |v| leaf.dist2(k, v)) {
                    self.visit_bucket(grid, x, y);
                }
            });
        }

        // Still not provably final (very uneven weights or sites): search the
        // rest depth first through the pyramid, nearer children first, skipping
        // the buckets already seen. Pruned nodes provably hold no site that
        // cuts the cell or dominates the site.
        self.stack.clear();
        let top = grid.levels.len() - 1;
        self.stack.push((grid.levels[top].dist2(0, p), top, 0));
        while let Some((d2, lvl, k)) = self.stack.pop() {
            let level = &grid.levels[lvl];
            if self.prune_box(d2, level.wmax[k], |v| level.dist2(k, v)) {
                continue;
            }
            let (x, y) = (k % level.nx, k / level.nx);
            if within_block(x, y, lvl, bx, by, RINGS) {
                continue; // every bucket under this node was seen above
            }
            if lvl == 0 {
                self.visit_bucket(grid, x, y);
                continue;
            }
            let down = &grid.levels[lvl - 1];
            let mut children = [(0.0, 0usize); 4];
            let mut count = 0;
            for cy in 2 * y..(2 * y + 2).min(down.ny) {
                for cx in 2 * x..(2 * x + 2).min(down.nx) {
                    let c = cy * down.nx + cx;
                    let cd2 = down.dist2(c, p);
                    if !self.prune_box(cd2, down.wmax[c], |v| down.dist2(c, v)) {
                        children[count] = (cd2, c);
                        count += 1;
                    }
                }
            }
            // Farthest pushed first so the nearest is popped first; the sort is
            // stable, so ties keep their (deterministic) scan order.
            let children = &mut children[..count];
            children.sort_by(|a, b| b.0.total_cmp(&a.0));
            self.stack
                .extend(children.iter().map(|&(cd2, c)| (cd2, lvl - 1, c)));
        }
        self.builder.finish(input.clip, input.edge_tol)
    }
}
