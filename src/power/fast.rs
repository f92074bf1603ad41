//! The fast path, [`power_diagram`]: each cell is built by clipping the clip
//! polygon with the bisectors of nearby sites, found through [`Grid`], until the
//! security radius proves no other site can cut. Owns the visiting order and the
//! parallel loop; may not change the clipping kernel or the output assembly.

use rayon::prelude::*;

use super::assemble::{cannot_cut, symmetrize, CellBuilder, Prepared};
use super::clip::LabelledPolygon;
use super::grid::Grid;
use super::{Cell, PowerDiagram, Site};
use crate::geom::ConvexPolygon;

/// From this many sites on, cells are built in parallel. Below it the thread
/// hand-off costs more than it saves.
const PARALLEL_FROM: usize = 512;

/// The first candidates (the 3 × 3 buckets around the site) are sorted by
/// distance so the cell shrinks fast; a block holding more than this many
/// sites (heavily clustered or coincident input) is taken in index order
/// instead, which is just as correct and avoids a quadratic sort cost.
const SORT_AT_MOST: usize = 64;

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
    let input = Prepared::new(sites, clip);
    let (lo, hi) = clip.bbox();
    let grid = Grid::new(&input.pos, &input.w, &input.usable, lo, hi);
    let n = input.len();
    let build = |state: &mut Walker, i: usize| -> Cell { state.cell(&input, &grid, i) };
    let mut cells: Vec<Cell> = if n >= PARALLEL_FROM {
        (0..n)
            .into_par_iter()
            .map_init(Walker::new, build)
            .collect()
    } else {
        let mut state = Walker::new();
        (0..n).map(|i| build(&mut state, i)).collect()
    };
    symmetrize(&mut cells);
    PowerDiagram { cells }
}

/// Per-thread scratch for building cells; its contents never influence results.
struct Walker {
    builder: CellBuilder,
    candidates: Vec<(f64, usize)>,
    /// Pending pyramid nodes: (squared distance lower bound, level, node).
    stack: Vec<(f64, usize, usize)>,
}

impl Walker {
    fn new() -> Self {
        Walker {
            builder: CellBuilder::new(LabelledPolygon::default()),
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

    fn cell(&mut self, input: &Prepared<'_>, grid: &Grid, i: usize) -> Cell {
        if !input.usable[i] {
            return super::assemble::empty_cell(input.pos[i], None);
        }
        self.builder.start(input, i);
        let p = self.builder.position();
        let (bx, by) = grid.bucket_xy(p);
        let leaf = &grid.levels[0];

        // Nearest candidates first: the 3 × 3 block of buckets around the site.
        self.candidates.clear();
        for y in by.saturating_sub(1)..(by + 2).min(leaf.ny) {
            for x in bx.saturating_sub(1)..(bx + 2).min(leaf.nx) {
                for &j in grid.bucket(x, y) {
                    if j != i {
                        self.candidates
                            .push(((input.pos[j] - p).length_squared(), j));
                    }
                }
            }
        }
        if self.candidates.len() <= SORT_AT_MOST {
            self.candidates
                .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        for &(_, j) in &self.candidates {
            self.builder.visit(input, j, true);
        }

        // Then everything else that might still matter, depth first through the
        // pyramid, nearer children first; pruned nodes provably hold no site that
        // cuts the cell or dominates the site.
        self.stack.clear();
        let top = grid.levels.len() - 1;
        self.stack.push((grid.levels[top].dist2(0, p), top, 0));
        while let Some((d2, lvl, k)) = self.stack.pop() {
            let level = &grid.levels[lvl];
            if self.prune(d2, level.wmax[k]) {
                continue;
            }
            let (x, y) = (k % level.nx, k / level.nx);
            if lvl == 0 {
                if x.abs_diff(bx) <= 1 && y.abs_diff(by) <= 1 {
                    continue; // already visited in the first block
                }
                for &j in grid.bucket(x, y) {
                    if j != i {
                        self.builder.visit(input, j, true);
                    }
                }
                continue;
            }
            let down = &grid.levels[lvl - 1];
            let mut children = [(0.0, 0usize); 4];
            let mut count = 0;
            for cy in 2 * y..(2 * y + 2).min(down.ny) {
                for cx in 2 * x..(2 * x + 2).min(down.nx) {
                    let c = cy * down.nx + cx;
                    let cd2 = down.dist2(c, p);
                    if !self.prune(cd2, down.wmax[c]) {
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
