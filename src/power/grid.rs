//! The spatial index of the fast path: a uniform bucket grid over the clip's
//! bounding box plus a pyramid of coarser levels, each node holding the bounding
//! box of its sites' true positions and their largest weight. Owns nothing but the
//! index; may not clip polygons or assemble diagrams.
//!
//! Sites outside the clip's box are clamped into the border buckets; because
//! every node stores the box of its sites' *true* positions, distance bounds stay
//! exact for them.

use crate::geom::Point;

/// Aim for about this many sites per leaf bucket.
const SITES_PER_BUCKET: usize = 2;

/// One level of the pyramid, row-major, `nx × ny` nodes.
#[derive(Clone, Debug)]
pub(crate) struct Level {
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    /// Lower corner of the box of the node's site positions (+∞ when empty).
    pub(crate) lo: Vec<Point>,
    /// Upper corner of that box (−∞ when empty).
    pub(crate) hi: Vec<Point>,
    /// Largest weight in the node (−∞ when empty).
    pub(crate) wmax: Vec<f64>,
}

/// Bucket grid plus pyramid. `levels[0]` is the leaf grid.
#[derive(Clone, Debug)]
pub(crate) struct Grid {
    origin: Point,
    cell: Point,
    pub(crate) levels: Vec<Level>,
    /// Leaf bucket `b` holds `items[start[b]..start[b + 1]]` (site indices, ascending).
    start: Vec<usize>,
    items: Vec<usize>,
    /// Positions and weights copied into bucket order, so that scanning a
    /// bucket reads contiguous memory instead of jumping through the site list.
    item_pos: Vec<Point>,
    item_w: Vec<f64>,
}

/// The sites of one leaf bucket: indices (ascending), positions, weights.
pub(crate) struct BucketSites<'g> {
    pub(crate) index: &'g [usize],
    pub(crate) pos: &'g [Point],
    pub(crate) w: &'g [f64],
}

impl Grid {
    /// Indexes the sites for which `usable[k]` holds, over the box `lo..hi`
    /// (which must have positive width and height).
    pub(crate) fn new(
        positions: &[Point],
        weights: &[f64],
        usable: &[bool],
        lo: Point,
        hi: Point,
    ) -> Self {
        let count = usable.iter().filter(|u| **u).count();
        let buckets = (count / SITES_PER_BUCKET).max(1);
        let size = (hi - lo).max(Point::splat(f64::MIN_POSITIVE));
        // Choose nx·ny ≈ buckets with roughly square buckets; rounding per axis
        // (rather than a fixed bucket side) keeps a long thin clip from getting
        // far more buckets than sites.
        let nx = ((buckets as f64 * size.x / size.y).sqrt().round() as usize).clamp(1, buckets);
        let ny = (buckets / nx).max(1);
        let cell = Point::new(size.x / nx as f64, size.y / ny as f64);
        let mut grid = Grid {
            origin: lo,
            cell,
            levels: Vec::new(),
            start: vec![0; nx * ny + 1],
            items: Vec::with_capacity(count),
            item_pos: Vec::new(),
            item_w: Vec::new(),
        };
        // Counting sort into buckets; indices stay ascending within a bucket.
        let bucket_of: Vec<usize> = positions
            .iter()
            .zip(usable)
            .map(|(p, u)| {
                if *u {
                    grid.bucket_of_xy(*p, nx, ny)
                } else {
                    usize::MAX
                }
            })
            .collect();
        for &b in &bucket_of {
            if b != usize::MAX {
                grid.start[b + 1] += 1;
            }
        }
        for b in 0..nx * ny {
            grid.start[b + 1] += grid.start[b];
        }
        let mut fill = grid.start.clone();
        grid.items.resize(count, 0);
        for (k, &b) in bucket_of.iter().enumerate() {
            if b != usize::MAX {
                grid.items[fill[b]] = k;
                fill[b] += 1;
            }
        }
        grid.item_pos = grid.items.iter().map(|&k| positions[k]).collect();
        grid.item_w = grid.items.iter().map(|&k| weights[k]).collect();
        let mut leaf = Level::empty(nx, ny);
        for b in 0..nx * ny {
            for &k in &grid.items[grid.start[b]..grid.start[b + 1]] {
                leaf.lo[b] = leaf.lo[b].min(positions[k]);
                leaf.hi[b] = leaf.hi[b].max(positions[k]);
                leaf.wmax[b] = leaf.wmax[b].max(weights[k]);
            }
        }
        grid.levels.push(leaf);
        while let Some(last) = grid.levels.last() {
            if last.nx == 1 && last.ny == 1 {
                break;
            }
            let next = last.coarsen();
            grid.levels.push(next);
        }
        grid
    }

    /// Leaf bucket coordinates of a point, clamped into the grid.
    pub(crate) fn bucket_xy(&self, p: Point) -> (usize, usize) {
        let leaf = &self.levels[0];
        let q = (p - self.origin) / self.cell;
        // `as usize` saturates and maps NaN to 0, so this never panics.
        let bx = q.x.floor().clamp(0.0, (leaf.nx - 1) as f64) as usize;
        let by = q.y.floor().clamp(0.0, (leaf.ny - 1) as f64) as usize;
        (bx, by)
    }

    fn bucket_of_xy(&self, p: Point, nx: usize, ny: usize) -> usize {
        let q = (p - self.origin) / self.cell;
        let bx = q.x.floor().clamp(0.0, (nx - 1) as f64) as usize;
        let by = q.y.floor().clamp(0.0, (ny - 1) as f64) as usize;
        by * nx + bx
    }

    /// Largest weight of any indexed site (−∞ when there is none).
    pub(crate) fn max_weight(&self) -> f64 {
        self.levels
            .last()
            .map_or(f64::NEG_INFINITY, |top| top.wmax[0])
    }

    /// A lower bound on the distance from a point `p` to any site in a bucket
    /// at Chebyshev distance `r` or more (`r ≥ 1`) from leaf bucket `(bx, by)`;
    /// +∞ when no such bucket exists. `p` need not lie in that bucket (the
    /// bound is then 0 where `p` is already beyond the block).
    ///
    /// Such a site's bucket column is `≤ bx − r` or `≥ bx + r` (or likewise its
    /// row). A site in column `c ≥ 1` has true `x ≥ origin + c·cell` and one in
    /// column `c ≤ nx − 2` has `x < origin + (c + 1)·cell`, clamped or not, so
    /// the distance to the nearest such column line bounds it. The result is
    /// shrunk by a hair so that round-off in bucket assignment cannot make it
    /// claim too much.
    pub(crate) fn ring_bound(&self, p: Point, bx: usize, by: usize, r: usize) -> f64 {
        let leaf = &self.levels[0];
        let side = |q: f64, o: f64, h: f64, b: usize, n: usize| -> f64 {
            let mut d = f64::INFINITY;
            if b >= r {
                d = d.min(q - (o + (b - r + 1) as f64 * h));
            }
            if b + r < n {
                d = d.min(o + (b + r) as f64 * h - q);
            }
            d
        };
        let d = side(p.x, self.origin.x, self.cell.x, bx, leaf.nx).min(side(
            p.y,
            self.origin.y,
            self.cell.y,
            by,
            leaf.ny,
        ));
        (d - 1e-9 * (self.cell.x + self.cell.y)).max(0.0)
    }

    /// Calls `f(x, y)` for every leaf bucket at Chebyshev distance exactly `r`
    /// from `(bx, by)`, row by row.
    pub(crate) fn for_ring(&self, bx: usize, by: usize, r: usize, mut f: impl FnMut(usize, usize)) {
        let leaf = &self.levels[0];
        let (x0, x1) = (bx.saturating_sub(r), (bx + r).min(leaf.nx - 1));
        let (y0, y1) = (by.saturating_sub(r), (by + r).min(leaf.ny - 1));
        for y in y0..=y1 {
            if y.abs_diff(by) == r {
                (x0..=x1).for_each(|x| f(x, y));
            } else {
                if bx >= r {
                    f(bx - r, y);
                }
                if bx + r < leaf.nx {
                    f(bx + r, y);
                }
            }
        }
    }

    /// The sites in leaf bucket `(bx, by)`, indices ascending.
    pub(crate) fn bucket(&self, bx: usize, by: usize) -> BucketSites<'_> {
        let b = by * self.levels[0].nx + bx;
        let range = self.start[b]..self.start[b + 1];
        BucketSites {
            index: &self.items[range.clone()],
            pos: &self.item_pos[range.clone()],
            w: &self.item_w[range],
        }
    }

    /// All indexed sites, bucket by bucket (row-major): an order in which
    /// consecutive sites are mostly near each other.
    pub(crate) fn spatial_order(&self) -> &[usize] {
        &self.items
    }
}

impl Level {
    fn empty(nx: usize, ny: usize) -> Self {
        Level {
            nx,
            ny,
            lo: vec![Point::splat(f64::INFINITY); nx * ny],
            hi: vec![Point::splat(f64::NEG_INFINITY); nx * ny],
            wmax: vec![f64::NEG_INFINITY; nx * ny],
        }
    }

    /// The next level up: each node covers 2 × 2 nodes of this one.
    fn coarsen(&self) -> Level {
        let (nx, ny) = (self.nx.div_ceil(2), self.ny.div_ceil(2));
        let mut up = Level::empty(nx, ny);
        for y in 0..self.ny {
            for x in 0..self.nx {
                let (k, u) = (y * self.nx + x, (y / 2) * nx + x / 2);
                up.lo[u] = up.lo[u].min(self.lo[k]);
                up.hi[u] = up.hi[u].max(self.hi[k]);
                up.wmax[u] = up.wmax[u].max(self.wmax[k]);
            }
        }
        up
    }

    /// Squared distance from `p` to the box of node `k` (+∞ for an empty node).
    #[inline]
    pub(crate) fn dist2(&self, k: usize, p: Point) -> f64 {
        let (lo, hi) = (self.lo[k], self.hi[k]);
        if lo.x > hi.x {
            return f64::INFINITY;
        }
        let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
        let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
        dx * dx + dy * dy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_usable_site_is_in_exactly_one_bucket() {
        let pos: Vec<Point> = (0..37)
            .map(|k| Point::new((k * 7 % 11) as f64 - 1.0, (k * 5 % 13) as f64))
            .collect();
        let w: Vec<f64> = (0..37).map(|k| k as f64).collect();
        let mut usable = vec![true; 37];
        usable[3] = false;
        let g = Grid::new(&pos, &w, &usable, Point::ZERO, Point::new(10.0, 12.0));
        let leaf = &g.levels[0];
        let mut seen = vec![0; 37];
        for by in 0..leaf.ny {
            for bx in 0..leaf.nx {
                let b = g.bucket(bx, by);
                assert!(b.index.windows(2).all(|w| w[0] < w[1]));
                for (n, &k) in b.index.iter().enumerate() {
                    assert_eq!((b.pos[n], b.w[n]), (pos[k], w[k]));
                    seen[k] += 1;
                    // The bucket's box holds the true position.
                    assert_eq!(leaf.dist2(by * leaf.nx + bx, pos[k]), 0.0);
                }
            }
        }
        for (k, s) in seen.iter().enumerate() {
            assert_eq!(*s, usize::from(k != 3));
        }
        let top = g.levels.last().expect("at least one level");
        assert_eq!((top.nx, top.ny), (1, 1));
        assert_eq!(top.wmax[0], 36.0);
    }
}
