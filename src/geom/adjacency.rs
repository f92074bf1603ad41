//! Level adjacency: which cells of one depth level (across all parents) share
//! an edge, as an undirected graph on node indices, and hop distances on it
//! (the paper's graph distance, §6). Built in about O(n) from a bucket grid
//! over the cells' bounding boxes; "share an edge" is `shared_length` above
//! the one threshold of `super::shared_edge`. Knows polygons and indices
//! only: the caller (a layout) says which polygon an index has.

use super::shared_edge::{shared_length, MIN_SHARED, PERPENDICULAR_TOL};
use super::{ConvexPolygon, Point};

/// Which cells of one level share an edge: an undirected graph on node indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelAdjacency {
    /// The level's node indices that have a cell, sorted, without duplicates.
    nodes: Vec<usize>,
    /// Adjacent pairs `(i, j)` of node indices with `i < j`, sorted.
    pairs: Vec<(usize, usize)>,
    /// `neighbours[offsets[i]..offsets[i + 1]]` are node `i`'s neighbours, sorted.
    /// Indexed by node index (length: largest node index + 2, or 0 when empty).
    offsets: Vec<usize>,
    /// All neighbour lists back to back.
    neighbors: Vec<usize>,
}

impl LevelAdjacency {
    /// The sorted neighbours of node `i`; empty for nodes not in the level.
    pub fn neighbors(&self, i: usize) -> &[usize] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => self.neighbors.get(s..e).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// True when nodes `i` and `j` share an edge.
    pub fn are_adjacent(&self, i: usize, j: usize) -> bool {
        self.neighbors(i).binary_search(&j).is_ok()
    }

    /// Every adjacent pair `(i, j)`, `i < j`, sorted.
    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }

    /// The node indices of the level that have a cell, sorted.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// One more than the largest node index a neighbour list exists for (0 when
    /// the level is empty): the size of per-node scratch arrays.
    fn universe(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }
}

/// Adjacency among the cells of `nodes` (one depth level, across all parents):
/// two cells are adjacent when [`shared_length`] ≥ [`MIN_SHARED`] × `scale`,
/// with perpendicular tolerance [`PERPENDICULAR_TOL`] × `scale`: the checker's
/// `adjacency`. `scale` is the layout's length scale (its
/// [`extent_diagonal`](super::shared_edge::extent_diagonal)); `polygon(i)` is
/// node `i`'s cell, `None` for an index without one (ignored, as are
/// duplicates in `nodes`).
///
/// Candidates come from a uniform grid over the cells' bounding boxes, so a level
/// of n similar-sized cells costs about O(n).
pub fn level_adjacency<'a>(
    polygon: impl Fn(usize) -> Option<&'a ConvexPolygon>,
    nodes: &[usize],
    scale: f64,
) -> LevelAdjacency {
    let ids = with_cells(&polygon, nodes);
    let pairs = adjacent_pairs_among(&polygon, &ids, scale, |_, _| true);
    LevelAdjacency::from_pairs(ids, pairs)
}

/// The pairs `(i, j)`, `i < j`, of [`level_adjacency`] among `nodes` for which
/// `consider(i, j)` holds, sorted; `consider` is asked before any polygon is
/// compared, so a caller that knows a pair cannot count (two cells of one
/// power diagram, two cells whose adjacency it already has) pays nothing for
/// it. Each pair kept is exactly one of [`level_adjacency`]'s.
pub fn adjacent_pairs<'a>(
    polygon: impl Fn(usize) -> Option<&'a ConvexPolygon>,
    nodes: &[usize],
    scale: f64,
    consider: impl Fn(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    let ids = with_cells(&polygon, nodes);
    adjacent_pairs_among(&polygon, &ids, scale, consider)
}

/// The indices of `nodes` that have a cell, sorted, without duplicates.
fn with_cells<'a>(
    polygon: &impl Fn(usize) -> Option<&'a ConvexPolygon>,
    nodes: &[usize],
) -> Vec<usize> {
    let mut ids: Vec<usize> = nodes
        .iter()
        .copied()
        .filter(|&i| polygon(i).is_some())
        .collect();
    ids.sort_unstable();
    ids.dedup();
    ids
}

/// How far a cell's bounding box is widened before boxes are compared: an
/// edge within the perpendicular tolerance of another's line may lie just
/// outside that cell's box.
pub fn box_pad(scale: f64) -> f64 {
    2.0 * PERPENDICULAR_TOL * scale
}

/// [`adjacent_pairs`] on `ids` (sorted, without duplicates, each with a cell).
fn adjacent_pairs_among<'a>(
    polygon: &impl Fn(usize) -> Option<&'a ConvexPolygon>,
    ids: &[usize],
    scale: f64,
    consider: impl Fn(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    if ids.is_empty() {
        return Vec::new();
    }
    let cell = |i: usize| polygon(i).expect("filtered to indices with a cell");
    let tol = PERPENDICULAR_TOL * scale;
    let threshold = MIN_SHARED * scale;
    let pad = box_pad(scale);
    let boxes: Vec<(Point, Point)> = ids
        .iter()
        .map(|&i| {
            let (lo, hi) = cell(i).bbox();
            (lo - Point::splat(pad), hi + Point::splat(pad))
        })
        .collect();
    let pairs = overlapping_boxes(&boxes, scale, |k, m| {
        // k < m, so ids[k] < ids[m]: the smaller node index goes first, as the
        // checker passes cells in file (= node) order.
        let (a, b) = (ids[k], ids[m]);
        consider(a, b) && shared_length(cell(a), cell(b), tol) >= threshold
    });
    pairs.into_iter().map(|(k, m)| (ids[k], ids[m])).collect()
}

/// Every pair `(k, m)`, `k < m`, of `boxes` (each `(lo, hi)`) that overlap,
/// edges included, and for which `accept(k, m)` holds, sorted. Candidates
/// come from a bucket grid, so n boxes of similar size cost about O(n);
/// `diag` is the length scale that bounds the buckets from below.
pub fn overlapping_boxes(
    boxes: &[(Point, Point)],
    diag: f64,
    accept: impl FnMut(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    if boxes.is_empty() {
        return Vec::new();
    }
    Grid::new(boxes, diag).candidate_pairs(boxes, accept)
}

impl LevelAdjacency {
    /// The graph on `nodes` with the edges `pairs` (node indices, each pair
    /// `(i, j)` with `i < j`), for callers that know which cells touch without
    /// comparing polygons (a power diagram lists its cells' neighbours).
    /// Duplicates are dropped; every pair's ends must be in `nodes`.
    pub fn from_pairs(mut nodes: Vec<usize>, mut pairs: Vec<(usize, usize)>) -> Self {
        nodes.sort_unstable();
        nodes.dedup();
        pairs.sort_unstable();
        pairs.dedup();
        debug_assert!(pairs.iter().all(|&(i, j)| i < j));
        let Some(&last) = nodes.last() else {
            return Self::default();
        };
        // Neighbour lists in CSR form, indexed by node index.
        let universe = last + 1;
        let mut offsets = vec![0usize; universe + 1];
        for &(i, j) in &pairs {
            offsets[i + 1] += 1;
            offsets[j + 1] += 1;
        }
        for i in 0..universe {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut neighbors = vec![0usize; offsets[universe]];
        for &(i, j) in &pairs {
            neighbors[fill[i]] = j;
            fill[i] += 1;
            neighbors[fill[j]] = i;
            fill[j] += 1;
        }
        // Pairs are sorted, so the lists already are; sorting again is cheap and
        // keeps `are_adjacent`'s binary search correct without that argument.
        for i in 0..universe {
            neighbors[offsets[i]..offsets[i + 1]].sort_unstable();
        }
        Self {
            nodes,
            pairs,
            offsets,
            neighbors,
        }
    }
}

/// A uniform grid of buckets over padded bounding boxes, in CSR form.
struct Grid {
    origin: Point,
    size: f64,
    nx: usize,
    ny: usize,
    /// `items[starts[b]..starts[b + 1]]` are the boxes touching bucket `b`, ascending.
    starts: Vec<usize>,
    items: Vec<usize>,
}

/// Largest number of buckets along one axis: keeps memory bounded whatever the
/// spread of cell sizes.
const MAX_BUCKETS_PER_AXIS: f64 = 4096.0;

impl Grid {
    /// Buckets about the size of a mean cell (like the checker), but never smaller
    /// than 1e-4 × `diag`, never so small that there are more than about four
    /// buckets per box, and never more than [`MAX_BUCKETS_PER_AXIS`] per axis.
    fn new(boxes: &[(Point, Point)], diag: f64) -> Self {
        let n = boxes.len().max(1) as f64;
        let mut lo = Point::splat(f64::INFINITY);
        let mut hi = Point::splat(f64::NEG_INFINITY);
        let mut extent_sum = 0.0;
        for &(l, h) in boxes {
            lo = lo.min(l);
            hi = hi.max(h);
            extent_sum += (h.x - l.x) + (h.y - l.y);
        }
        let span = (hi - lo).max(Point::ZERO);
        let mean = extent_sum / (2.0 * n);
        let mut size = mean
            .max(diag * 1e-4)
            .max((span.x * span.y / (4.0 * n)).sqrt())
            .max(span.x / MAX_BUCKETS_PER_AXIS)
            .max(span.y / MAX_BUCKETS_PER_AXIS);
        if !(size > 0.0 && size.is_finite()) {
            size = 1.0;
        }
        let mut grid = Self {
            origin: lo,
            size,
            nx: 1,
            ny: 1,
            starts: Vec::new(),
            items: Vec::new(),
        };
        grid.nx = grid.coord(hi.x, lo.x, 1 << 13) + 1;
        grid.ny = grid.coord(hi.y, lo.y, 1 << 13) + 1;
        let buckets = grid.nx * grid.ny;
        let mut counts = vec![0usize; buckets + 1];
        for b in boxes {
            grid.for_buckets(b, |k| counts[k + 1] += 1);
        }
        for k in 0..buckets {
            counts[k + 1] += counts[k];
        }
        let mut fill = counts.clone();
        let mut items = vec![0usize; counts[buckets]];
        for (i, b) in boxes.iter().enumerate() {
            grid.for_buckets(b, |k| {
                items[fill[k]] = i;
                fill[k] += 1;
            });
        }
        grid.starts = counts;
        grid.items = items;
        grid
    }

    /// Bucket number along one axis of coordinate `x`, clamped to `[0, max]`.
    fn coord(&self, x: f64, origin: f64, max: usize) -> usize {
        let c = ((x - origin) / self.size).floor();
        // `as` saturates (NaN to 0), so no input can wrap; the clamp keeps the
        // index inside the grid.
        let c = if c > 0.0 { c as usize } else { 0 };
        c.min(max)
    }

    /// Calls `f` with every bucket the box touches.
    fn for_buckets(&self, (lo, hi): &(Point, Point), mut f: impl FnMut(usize)) {
        let x0 = self.coord(lo.x, self.origin.x, self.nx - 1);
        let x1 = self.coord(hi.x, self.origin.x, self.nx - 1);
        let y0 = self.coord(lo.y, self.origin.y, self.ny - 1);
        let y1 = self.coord(hi.y, self.origin.y, self.ny - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                f(y * self.nx + x);
            }
        }
    }

    /// Every pair `(k, m)`, `k < m`, of boxes that overlap and for which
    /// `accept(k, m)` holds, sorted.
    fn candidate_pairs(
        &self,
        boxes: &[(Point, Point)],
        mut accept: impl FnMut(usize, usize) -> bool,
    ) -> Vec<(usize, usize)> {
        // `stamp[m] == k` marks m as already collected for box k, so each pair
        // is tested once even when the boxes share several buckets.
        let mut stamp = vec![usize::MAX; boxes.len()];
        let mut candidates = Vec::new();
        let mut pairs = Vec::new();
        for (k, bk) in boxes.iter().enumerate() {
            candidates.clear();
            self.for_buckets(bk, |bucket| {
                let range = self.starts[bucket]..self.starts[bucket + 1];
                for &m in &self.items[range] {
                    if m > k && stamp[m] != k {
                        stamp[m] = k;
                        candidates.push(m);
                    }
                }
            });
            candidates.sort_unstable();
            for &m in &candidates {
                let bm = &boxes[m];
                let overlap =
                    bk.0.x <= bm.1.x && bm.0.x <= bk.1.x && bk.0.y <= bm.1.y && bm.0.y <= bk.1.y;
                if overlap && accept(k, m) {
                    pairs.push((k, m));
                }
            }
        }
        pairs
    }
}

/// Breadth-first search from `source` over `adj`, stopping once every node with
/// `want[v] == tag` has been reached (`remaining` of them). `dist` must be all
/// `usize::MAX` on entry; the nodes it sets are appended to `touched`.
fn bfs(
    adj: &LevelAdjacency,
    source: usize,
    want: &[usize],
    tag: usize,
    mut remaining: usize,
    dist: &mut [usize],
    touched: &mut Vec<usize>,
) {
    if source >= dist.len() {
        return;
    }
    let start = touched.len();
    dist[source] = 0;
    touched.push(source);
    if want[source] == tag {
        remaining = remaining.saturating_sub(1);
    }
    let mut head = start;
    while remaining > 0 && head < touched.len() {
        let u = touched[head];
        head += 1;
        let du = dist[u];
        for &v in adj.neighbors(u) {
            if dist[v] == usize::MAX {
                dist[v] = du + 1;
                touched.push(v);
                if want[v] == tag {
                    remaining -= 1;
                    if remaining == 0 {
                        return;
                    }
                }
            }
        }
    }
}

/// Hop count of a shortest path from node `a` to node `b` in `adj`; `Some(0)` when
/// `a == b`, `None` when no path exists (or either node is not in the level).
pub fn hop_distance(adj: &LevelAdjacency, a: usize, b: usize) -> Option<usize> {
    hop_distances(adj, &[(a, b)]).pop().flatten()
}

/// [`hop_distance`] for many pairs, in the order given. Runs one breadth-first
/// search per distinct source (the smaller index of each pair), stopping as soon
/// as all of that source's targets are reached.
pub fn hop_distances(adj: &LevelAdjacency, pairs: &[(usize, usize)]) -> Vec<Option<usize>> {
    let mut out = vec![None; pairs.len()];
    let universe = adj.universe();
    // Canonical (source, target) with source <= target; the graph is undirected.
    let mut order: Vec<(usize, usize, usize)> = pairs
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| (a.min(b), a.max(b), k))
        .collect();
    order.sort_unstable();
    let mut dist = vec![usize::MAX; universe];
    let mut want = vec![usize::MAX; universe];
    let mut touched = Vec::new();
    let mut g = 0;
    while g < order.len() {
        let source = order[g].0;
        let end = g + order[g..].iter().take_while(|p| p.0 == source).count();
        // Distinct targets of this source, tagged with the group start `g`.
        let mut remaining = 0;
        for &(_, t, _) in &order[g..end] {
            if t < universe && want[t] != g {
                want[t] = g;
                remaining += 1;
            }
        }
        bfs(adj, source, &want, g, remaining, &mut dist, &mut touched);
        for &(s, t, k) in &order[g..end] {
            out[k] = if s == t {
                Some(0)
            } else {
                dist.get(t).copied().filter(|&d| d != usize::MAX)
            };
        }
        for v in touched.drain(..) {
            dist[v] = usize::MAX;
        }
        g = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::shared_edge::extent_diagonal;
    use crate::rng::Rng;

    fn rect(x: f64, y: f64, w: f64, h: f64) -> ConvexPolygon {
        ConvexPolygon::rectangle(x, y, w, h).expect("valid rectangle")
    }

    fn adjacency_of(polys: &[ConvexPolygon], nodes: &[usize]) -> LevelAdjacency {
        let scale = extent_diagonal(polys).unwrap_or(1.0);
        level_adjacency(|i| polys.get(i), nodes, scale)
    }

    /// An n × n grid of unit squares, row by row.
    fn grid_layout(n: usize) -> Vec<ConvexPolygon> {
        (0..n * n)
            .map(|k| rect((k % n) as f64, (k / n) as f64, 1.0, 1.0))
            .collect()
    }

    /// Voronoi cells of random points in a `w` × `h` rectangle, by clipping the
    /// rectangle with every bisector (O(n²), fine for a test).
    fn random_voronoi(n: usize, w: f64, h: f64, seed: u64) -> Vec<ConvexPolygon> {
        let mut rng = Rng::new(seed);
        let sites: Vec<Point> = (0..n)
            .map(|_| Point::new(rng.next_f64() * w, rng.next_f64() * h))
            .collect();
        sites
            .iter()
            .map(|&p| {
                let mut cell = rect(0.0, 0.0, w, h);
                for &q in &sites {
                    if q == p {
                        continue;
                    }
                    // Points x closer to p than to q: (q − p)·x ≤ (|q|² − |p|²) / 2.
                    let normal = q - p;
                    let offset = 0.5 * (q.length_squared() - p.length_squared());
                    cell = cell
                        .clip_halfplane(normal, offset)
                        .expect("site keeps its cell");
                }
                cell
            })
            .collect()
    }

    #[test]
    fn three_by_three_grid() {
        let cells = grid_layout(3);
        let all: Vec<usize> = (0..9).collect();
        let adj = adjacency_of(&cells, &all);
        assert_eq!(adj.pairs().len(), 12);
        assert_eq!(adj.neighbors(4), &[1, 3, 5, 7]);
        assert_eq!(adj.neighbors(0), &[1, 3]);
        assert!(adj.are_adjacent(0, 1) && adj.are_adjacent(1, 0));
        assert!(!adj.are_adjacent(0, 4));
        assert!(!adj.are_adjacent(0, 100));
        assert_eq!(hop_distance(&adj, 0, 8), Some(4));
        assert_eq!(hop_distance(&adj, 8, 0), Some(4));
        assert_eq!(hop_distance(&adj, 2, 2), Some(0));
        assert_eq!(
            hop_distances(&adj, &[(0, 8), (0, 4), (6, 2), (0, 1), (4, 4)]),
            vec![Some(4), Some(2), Some(4), Some(1), Some(0)]
        );
    }

    #[test]
    fn unreachable_and_foreign_nodes() {
        let cells = grid_layout(3);
        // Corners only: none touches another along an edge.
        let adj = adjacency_of(&cells, &[8, 0, 2, 6, 0, 99]);
        assert_eq!(adj.nodes(), &[0, 2, 6, 8]);
        assert!(adj.pairs().is_empty());
        assert_eq!(hop_distance(&adj, 0, 8), None);
        assert_eq!(hop_distance(&adj, 0, 99), None);
        assert_eq!(hop_distance(&adj, 99, 0), None);
        let empty = adjacency_of(&cells, &[]);
        assert!(empty.pairs().is_empty() && empty.neighbors(0).is_empty());
        assert_eq!(hop_distances(&empty, &[(0, 1)]), vec![None]);
    }

    #[test]
    fn grid_matches_brute_force_on_random_voronoi() {
        for seed in [1u64, 2, 3] {
            let cells = random_voronoi(300, 1000.0, 600.0, seed);
            let n = cells.len();
            let all: Vec<usize> = (0..n).collect();
            let adj = adjacency_of(&cells, &all);
            let diag = extent_diagonal(&cells).expect("cells");
            assert!((diag - Point::new(1000.0, 600.0).length()).abs() < 1e-9);
            let tol = PERPENDICULAR_TOL * diag;
            let mut brute = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    let s = shared_length(&cells[i], &cells[j], tol);
                    if s >= MIN_SHARED * diag {
                        brute.push((i, j));
                    }
                }
            }
            assert_eq!(adj.pairs(), brute.as_slice(), "seed {seed}");
            // A planar Voronoi tiling of n sites has between n − 1 and 3n − 6 edges.
            assert!(brute.len() >= n - 1 && brute.len() <= 3 * n - 6);
            // Shared hop distances agree with one search per pair.
            let queries: Vec<(usize, usize)> = (0..n).map(|k| (k, (k * 7 + 3) % n)).collect();
            let shared = hop_distances(&adj, &queries);
            for (q, d) in queries.iter().zip(&shared) {
                assert_eq!(hop_distance(&adj, q.0, q.1), *d);
                assert!(d.is_some(), "a Voronoi tiling is connected");
            }
        }
    }
}
