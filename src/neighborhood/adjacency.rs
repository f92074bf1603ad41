//! Level-wide cell adjacency from finished polygons (which cells share an edge),
//! hop distances on that adjacency graph, and the paper's Table 2 metrics
//! (method-reference §7). "Share an edge" is defined exactly as in the
//! independent checker `shared/tools/check-layout`, so the `realized` flags this
//! crate writes always agree with it. Pure: no I/O, no clock.

use crate::geom::{cross, ConvexPolygon, Point};
use crate::layout::Layout;
use nptreemap_formats::Dataset;

/// Default shortest shared boundary, as a fraction of the layout diagonal, for two
/// cells to count as adjacent (the checker's `--min-shared` default).
pub const DEFAULT_MIN_SHARED: f64 = 1e-6;

/// Perpendicular tolerance, as a fraction of the layout diagonal, within which an
/// edge of one cell lies on an edge of the other (the checker's `tol_d`).
pub const PERPENDICULAR_TOL: f64 = 1e-5;

/// Calls `f(p1, u, lo, hi)` for every overlap of an edge of `a` (from `p1` along
/// the unit direction `u`) with an edge of `b` lying within `tol` of its line; the
/// overlap is the parameter interval `[lo, hi]` along `u`, with `hi > lo`.
///
/// This is the checker's `shared_length` loop verbatim (same edge order, same
/// tests), so the sums agree with it to round-off.
fn for_each_overlap(
    a: &ConvexPolygon,
    b: &ConvexPolygon,
    tol: f64,
    mut f: impl FnMut(Point, Point, f64, f64),
) {
    let pa = a.points();
    let pb = b.points();
    let (na, nb) = (pa.len(), pb.len());
    for i in 0..na {
        let p1 = pa[i];
        let e = pa[(i + 1) % na] - p1;
        let length = e.length();
        // Not `== 0.0` alone: a non-finite length would poison every overlap.
        if length <= 0.0 || !length.is_finite() {
            continue;
        }
        let u = e / length;
        for j in 0..nb {
            let q1 = pb[j];
            let q2 = pb[(j + 1) % nb];
            // Both end points of b's edge must lie on a's edge line (within tol):
            // then the edges are collinear and only the overlap along u is left.
            if cross(u, q1 - p1).abs() > tol || cross(u, q2 - p1).abs() > tol {
                continue;
            }
            let t1 = u.dot(q1 - p1);
            let t2 = u.dot(q2 - p1);
            let lo = t1.min(t2).max(0.0);
            let hi = t1.max(t2).min(length);
            if hi > lo {
                f(p1, u, lo, hi);
            }
        }
    }
}

/// Total length of boundary that `a` and `b` have in common: the summed overlap
/// of collinear edges, an edge of `b` counting as on an edge of `a` when both its
/// end points are within `tol` of that edge's line. Touching at a vertex gives 0.
/// Same definition and edge order as the checker's `shared_length`.
pub fn shared_length(a: &ConvexPolygon, b: &ConvexPolygon, tol: f64) -> f64 {
    let mut total = 0.0;
    for_each_overlap(a, b, tol, |_, _, lo, hi| total += hi - lo);
    total
}

/// The pieces of boundary that `a` and `b` have in common (see [`shared_length`]),
/// as segments on `a`'s edges, in `a`'s edge order, each running in `a`'s
/// direction. Their lengths sum to [`shared_length`].
pub fn shared_segments(a: &ConvexPolygon, b: &ConvexPolygon, tol: f64) -> Vec<[Point; 2]> {
    let mut out = Vec::new();
    for_each_overlap(a, b, tol, |p1, u, lo, hi| {
        out.push([p1 + u * lo, p1 + u * hi]);
    });
    out
}

/// The length scale of a layout used for adjacency thresholds: the diagonal of the
/// bounding box of every cell's vertices, exactly as the checker computes it from
/// the polygons (for the default rectangle outline this is the canvas diagonal).
/// Falls back to the canvas diagonal when there are no cells, and to 1 when that
/// is zero or not finite, as the checker does.
pub fn layout_diagonal(layout: &Layout) -> f64 {
    let mut bounds: Option<(Point, Point)> = None;
    for cell in &layout.cells {
        let (lo, hi) = cell.polygon.bbox();
        bounds = Some(match bounds {
            None => (lo, hi),
            Some((l, h)) => (l.min(lo), h.max(hi)),
        });
    }
    let diag = match bounds {
        Some((lo, hi)) => (hi - lo).length(),
        None => Point::new(layout.canvas.width, layout.canvas.height).length(),
    };
    if diag > 0.0 && diag.is_finite() {
        diag
    } else {
        1.0
    }
}

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
    neighbours: Vec<usize>,
}

impl LevelAdjacency {
    /// The sorted neighbours of node `i`; empty for nodes not in the level.
    pub fn neighbours(&self, i: usize) -> &[usize] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => self.neighbours.get(s..e).unwrap_or(&[]),
            _ => &[],
        }
    }

    /// True when nodes `i` and `j` share an edge.
    pub fn are_adjacent(&self, i: usize, j: usize) -> bool {
        self.neighbours(i).binary_search(&j).is_ok()
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
/// two cells are adjacent when [`shared_length`] ≥ `min_shared` × the layout
/// diagonal ([`layout_diagonal`]), with perpendicular tolerance
/// [`PERPENDICULAR_TOL`] × diagonal — the checker's `adjacency`.
///
/// Candidates come from a uniform grid over the cells' bounding boxes, so a level
/// of n similar-sized cells costs about O(n). Node indices without a cell in
/// `layout` are ignored; duplicates count once.
pub fn level_adjacency(layout: &Layout, nodes: &[usize], min_shared: f64) -> LevelAdjacency {
    let mut ids: Vec<usize> = nodes
        .iter()
        .copied()
        .filter(|&i| i < layout.cells.len())
        .collect();
    ids.sort_unstable();
    ids.dedup();
    let Some(&last) = ids.last() else {
        return LevelAdjacency::default();
    };

    let diag = layout_diagonal(layout);
    let tol = PERPENDICULAR_TOL * diag;
    let threshold = min_shared * diag;
    let pad = 2.0 * tol;
    let boxes: Vec<(Point, Point)> = ids
        .iter()
        .map(|&i| {
            let (lo, hi) = layout.cells[i].polygon.bbox();
            (lo - Point::splat(pad), hi + Point::splat(pad))
        })
        .collect();
    let grid = Grid::new(&boxes, diag);
    let pairs = grid.candidate_pairs(&boxes, |k, m| {
        // k < m, so ids[k] < ids[m]: the smaller node index goes first, as the
        // checker passes cells in file (= node) order.
        let (a, b) = (ids[k], ids[m]);
        shared_length(&layout.cells[a].polygon, &layout.cells[b].polygon, tol) >= threshold
    });
    let pairs: Vec<(usize, usize)> = pairs.into_iter().map(|(k, m)| (ids[k], ids[m])).collect();

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
    let mut neighbours = vec![0usize; offsets[universe]];
    for &(i, j) in &pairs {
        neighbours[fill[i]] = j;
        fill[i] += 1;
        neighbours[fill[j]] = i;
        fill[j] += 1;
    }
    // Pairs are sorted, so the lists already are; sorting again is cheap and
    // keeps `are_adjacent`'s binary search correct without that argument.
    for i in 0..universe {
        neighbours[offsets[i]..offsets[i + 1]].sort_unstable();
    }
    LevelAdjacency {
        nodes: ids,
        pairs,
        offsets,
        neighbours,
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
        for &v in adj.neighbours(u) {
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

/// The paper's Table 2 figures for one layout (method-reference §7).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalMetrics {
    /// Depth levels, the root level included (max depth + 1).
    pub levels: usize,
    /// Nodes, the root and virtual nodes included.
    pub nodes: usize,
    /// Nodes without children.
    pub leaves: usize,
    /// Constraint pairs at the deepest level (as given, duplicates included).
    pub leaf_constraints: usize,
    /// Constraint pairs whose cells share an edge.
    pub realized: usize,
    /// `100 × realized / leaf_constraints`; 0 when there are no constraints.
    pub realized_pct: f64,
    /// Mean over the leaf level's diagrams (the parents of the deepest nodes,
    /// single-child diagrams included) of Σ|A* − A| / A(parent), A* the target
    /// area from node values. Diagrams whose parent has no area or whose children
    /// have no value are skipped, as the checker does; 0 when none is left.
    pub area_error: f64,
    /// Median hop distance over the constraint pairs joined by a path (the mean of
    /// the middle two for an even count); `None` when no pair is joined.
    pub graph_distance_median: Option<f64>,
    /// Largest hop distance over the constraint pairs joined by a path.
    pub graph_distance_max: Option<usize>,
    /// Mean over leaves of the bounding box's long side / short side (§10 row 17,
    /// `avg_aspect_ratio`); leaves with a zero-width box are skipped; 0 when none.
    pub aspect_ratio: f64,
    /// The prototype's figure (§7, `avg_aspect_ratio_proto`): mean bounding-box
    /// width / height over every non-root cell of every level, virtual nodes
    /// included; cells with zero height are skipped; 0 when none.
    pub aspect_ratio_proto: f64,
}

/// Mean of the values, 0 when there are none.
fn mean(sum: f64, count: usize) -> f64 {
    if count > 0 {
        sum / count as f64
    } else {
        0.0
    }
}

/// Computes [`EvalMetrics`]. `leaf_pairs` are the constraint pairs (node indices)
/// at the deepest level; realized means adjacent in the deepest level's
/// [`level_adjacency`] with [`DEFAULT_MIN_SHARED`]. Nodes without a cell in
/// `layout` are skipped rather than trusted.
pub fn eval_metrics(
    dataset: &Dataset,
    layout: &Layout,
    leaf_pairs: &[(usize, usize)],
) -> EvalMetrics {
    let nodes = dataset.nodes();
    let cells = &layout.cells;
    let max_depth = dataset.max_depth();
    let deepest: Vec<usize> = (0..nodes.len())
        .filter(|&i| nodes[i].depth == max_depth)
        .collect();
    let adj = level_adjacency(layout, &deepest, DEFAULT_MIN_SHARED);

    let realized = leaf_pairs
        .iter()
        .filter(|&&(a, b)| adj.are_adjacent(a, b))
        .count();
    let mut hops: Vec<usize> = hop_distances(&adj, leaf_pairs)
        .into_iter()
        .flatten()
        .collect();
    hops.sort_unstable();
    let graph_distance_median = match hops.len() {
        0 => None,
        n if n % 2 == 1 => Some(hops[n / 2] as f64),
        n => Some((hops[n / 2 - 1] + hops[n / 2]) as f64 / 2.0),
    };

    // Leaf-level diagrams: the distinct parents of the deepest nodes, in node order.
    let mut parents: Vec<usize> = deepest.iter().filter_map(|&i| nodes[i].parent).collect();
    parents.sort_unstable();
    parents.dedup();
    let (mut err_sum, mut diagrams) = (0.0, 0usize);
    for p in parents {
        let Some(parent_cell) = cells.get(p) else {
            continue;
        };
        let kids = &nodes[p].children;
        let total: f64 = kids
            .iter()
            .filter_map(|&c| nodes.get(c))
            .map(|n| n.value)
            .sum();
        let area = parent_cell.polygon.area();
        if !(total > 0.0 && area > 0.0) {
            continue;
        }
        let mut err = 0.0;
        for &c in kids {
            if let (Some(node), Some(cell)) = (nodes.get(c), cells.get(c)) {
                // |A* − A| / A(parent) with A* = value / total × A(parent).
                err += (node.value / total - cell.polygon.area() / area).abs();
            }
        }
        err_sum += err;
        diagrams += 1;
    }

    let (mut leaves, mut ar_sum, mut ar_count) = (0usize, 0.0, 0usize);
    let (mut proto_sum, mut proto_count) = (0.0, 0usize);
    for (i, node) in nodes.iter().enumerate() {
        let is_leaf = node.children.is_empty();
        leaves += usize::from(is_leaf);
        let Some(cell) = cells.get(i) else {
            continue;
        };
        let (lo, hi) = cell.polygon.bbox();
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        if is_leaf && w.min(h) > 0.0 {
            ar_sum += w.max(h) / w.min(h);
            ar_count += 1;
        }
        if node.parent.is_some() && h > 0.0 {
            proto_sum += w / h;
            proto_count += 1;
        }
    }

    EvalMetrics {
        levels: max_depth + 1,
        nodes: nodes.len(),
        leaves,
        leaf_constraints: leaf_pairs.len(),
        realized,
        realized_pct: mean(100.0 * realized as f64, leaf_pairs.len()),
        area_error: mean(err_sum, diagrams),
        graph_distance_median,
        graph_distance_max: hops.last().copied(),
        aspect_ratio: mean(ar_sum, ar_count),
        aspect_ratio_proto: mean(proto_sum, proto_count),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{Canvas, LayoutCell};
    use nptreemap_formats::{DatasetBuilder, NodeSpec};

    fn rect(x: f64, y: f64, w: f64, h: f64) -> ConvexPolygon {
        ConvexPolygon::rectangle(x, y, w, h).expect("valid rectangle")
    }

    fn layout_of(canvas: Canvas, polys: Vec<ConvexPolygon>) -> Layout {
        Layout {
            canvas,
            cells: polys
                .into_iter()
                .map(|polygon| LayoutCell {
                    site: polygon.centroid(),
                    power_weight: 0.0,
                    polygon,
                })
                .collect(),
        }
    }

    /// An n × n grid of unit squares, row by row.
    fn grid_layout(n: usize) -> Layout {
        let side = n as f64;
        let polys = (0..n * n)
            .map(|k| rect((k % n) as f64, (k / n) as f64, 1.0, 1.0))
            .collect();
        layout_of(
            Canvas {
                width: side,
                height: side,
            },
            polys,
        )
    }

    use crate::rng::Rng;

    /// Voronoi cells of random points in a `w` × `h` rectangle, by clipping the
    /// rectangle with every bisector (O(n²), fine for a test).
    fn random_voronoi(n: usize, w: f64, h: f64, seed: u64) -> Layout {
        let mut rng = Rng::new(seed);
        let sites: Vec<Point> = (0..n)
            .map(|_| Point::new(rng.next_f64() * w, rng.next_f64() * h))
            .collect();
        let polys = sites
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
            .collect();
        layout_of(
            Canvas {
                width: w,
                height: h,
            },
            polys,
        )
    }

    #[test]
    fn squares_sharing_a_side() {
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 0.0, 1.0, 1.0);
        assert!((shared_length(&a, &b, 1e-9) - 1.0).abs() < 1e-12);
        assert!((shared_length(&b, &a, 1e-9) - 1.0).abs() < 1e-12);
        let segs = shared_segments(&a, &b, 1e-9);
        assert_eq!(segs.len(), 1);
        assert!((segs[0][0] - segs[0][1]).length() - 1.0 < 1e-12);
        assert!(segs[0].iter().all(|p| (p.x - 1.0).abs() < 1e-12));
    }

    #[test]
    fn squares_touching_at_a_corner_share_nothing() {
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 1.0, 1.0, 1.0);
        assert_eq!(shared_length(&a, &b, 1e-9), 0.0);
        assert!(shared_segments(&a, &b, 1e-9).is_empty());
    }

    #[test]
    fn partial_overlap_of_collinear_edges() {
        // a's right side is x = 1, y in [0, 1]; b's left side is x = 1, y in
        // [0.5, 1.5]: they overlap on y in [0.5, 1], length 0.5.
        let a = rect(0.0, 0.0, 1.0, 1.0);
        let b = rect(1.0, 0.5, 1.0, 1.0);
        assert!((shared_length(&a, &b, 1e-9) - 0.5).abs() < 1e-12);
        let segs = shared_segments(&a, &b, 1e-9);
        assert_eq!(segs.len(), 1);
        let ys = [
            segs[0][0].y.min(segs[0][1].y),
            segs[0][0].y.max(segs[0][1].y),
        ];
        assert!((ys[0] - 0.5).abs() < 1e-12 && (ys[1] - 1.0).abs() < 1e-12);
        // Within the perpendicular tolerance a small gap still counts as shared.
        let c = rect(1.0 + 1e-7, 0.0, 1.0, 1.0);
        assert!((shared_length(&a, &c, 1e-6) - 1.0).abs() < 1e-9);
        assert_eq!(shared_length(&a, &c, 1e-8), 0.0);
    }

    #[test]
    fn three_by_three_grid() {
        let layout = grid_layout(3);
        let all: Vec<usize> = (0..9).collect();
        let adj = level_adjacency(&layout, &all, DEFAULT_MIN_SHARED);
        assert_eq!(adj.pairs().len(), 12);
        assert_eq!(adj.neighbours(4), &[1, 3, 5, 7]);
        assert_eq!(adj.neighbours(0), &[1, 3]);
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
        let layout = grid_layout(3);
        // Corners only: none touches another along an edge.
        let adj = level_adjacency(&layout, &[8, 0, 2, 6, 0, 99], DEFAULT_MIN_SHARED);
        assert_eq!(adj.nodes(), &[0, 2, 6, 8]);
        assert!(adj.pairs().is_empty());
        assert_eq!(hop_distance(&adj, 0, 8), None);
        assert_eq!(hop_distance(&adj, 0, 99), None);
        assert_eq!(hop_distance(&adj, 99, 0), None);
        let empty = level_adjacency(&layout, &[], DEFAULT_MIN_SHARED);
        assert!(empty.pairs().is_empty() && empty.neighbours(0).is_empty());
        assert_eq!(hop_distances(&empty, &[(0, 1)]), vec![None]);
    }

    #[test]
    fn grid_matches_brute_force_on_random_voronoi() {
        for seed in [1u64, 2, 3] {
            let layout = random_voronoi(300, 1000.0, 600.0, seed);
            let n = layout.cells.len();
            let all: Vec<usize> = (0..n).collect();
            let adj = level_adjacency(&layout, &all, DEFAULT_MIN_SHARED);
            let diag = layout_diagonal(&layout);
            assert!((diag - Point::new(1000.0, 600.0).length()).abs() < 1e-9);
            let tol = PERPENDICULAR_TOL * diag;
            let mut brute = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    let s = shared_length(&layout.cells[i].polygon, &layout.cells[j].polygon, tol);
                    if s >= DEFAULT_MIN_SHARED * diag {
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

    #[test]
    fn eval_metrics_by_hand() -> Result<(), nptreemap_formats::ModelError> {
        // Nodes in BFS order: 0 root, 1 A, 2 B, 3 a1 (1), 4 a2 (2), 5 b1 (1).
        let mut b = DatasetBuilder::new();
        b.add(NodeSpec::new("root"));
        b.add(NodeSpec::new("A").parent("root"));
        b.add(NodeSpec::new("B").parent("root"));
        b.add(NodeSpec::new("a1").parent("A").weight(1.0));
        b.add(NodeSpec::new("a2").parent("A").weight(2.0));
        b.add(NodeSpec::new("b1").parent("B").weight(1.0));
        let ds = b.build()?;
        assert_eq!(ds.node(3).id, "a1");
        // Canvas 4 × 2: A = [0,3]×[0,2], B = [3,4]×[0,2]; a1 and a2 halve A
        // (1.5 × 2 each), b1 fills B.
        let layout = layout_of(
            Canvas {
                width: 4.0,
                height: 2.0,
            },
            vec![
                rect(0.0, 0.0, 4.0, 2.0),
                rect(0.0, 0.0, 3.0, 2.0),
                rect(3.0, 0.0, 1.0, 2.0),
                rect(0.0, 0.0, 1.5, 2.0),
                rect(1.5, 0.0, 1.5, 2.0),
                rect(3.0, 0.0, 1.0, 2.0),
            ],
        );
        // Leaf adjacency: a1–a2 (x = 1.5) and a2–b1 (x = 3); a1–b1 apart.
        // Constraints (a1, b1) and (a1, a2): one realized (50 %); hops 2 and 1,
        // so median 1.5 and max 2.
        // Area error: diagram A has targets 2 and 4 (A = 6, values 1 : 2) against
        // areas 3 and 3, so (1 + 1) / 6 = 1/3; diagram B (single child) 0;
        // mean 1/6.
        // Aspect (leaves, long/short): a1 2/1.5 = 4/3, a2 4/3, b1 2; mean 14/9.
        // Aspect (proto, w/h of non-root cells): A 1.5, B 0.5, a1 0.75, a2 0.75,
        // b1 0.5; sum 4, mean 0.8.
        let m = eval_metrics(&ds, &layout, &[(3, 5), (3, 4)]);
        assert_eq!(m.levels, 3);
        assert_eq!(m.nodes, 6);
        assert_eq!(m.leaves, 3);
        assert_eq!(m.leaf_constraints, 2);
        assert_eq!(m.realized, 1);
        assert!((m.realized_pct - 50.0).abs() < 1e-12);
        assert!((m.area_error - 1.0 / 6.0).abs() < 1e-12);
        assert_eq!(m.graph_distance_median, Some(1.5));
        assert_eq!(m.graph_distance_max, Some(2));
        assert!((m.aspect_ratio - 14.0 / 9.0).abs() < 1e-12);
        assert!((m.aspect_ratio_proto - 0.8).abs() < 1e-12);

        // A layout missing cells and pairs naming no node must not panic.
        let short = Layout {
            canvas: layout.canvas,
            cells: layout.cells[..2].to_vec(),
        };
        let m = eval_metrics(&ds, &short, &[(3, 5), (100, 200)]);
        assert_eq!(m.realized, 0);
        assert_eq!(m.graph_distance_median, None);
        Ok(())
    }
}
