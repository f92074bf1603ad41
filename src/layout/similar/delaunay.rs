//! The Delaunay graph of one diagram's sites (spade), the neighbor optimiser's
//! planar, linear-size candidate graph, and the constraint edges it finds one
//! flip away (paper §9: realise chosen constraints through the dual).
//!
//! The graph is a candidate graph only: a power diagram's own adjacency equals
//! the Delaunay graph of its sites when the weights are equal, and the weights
//! of a treemap never are, so what it proposes is always confirmed on the real
//! cells (see `swap::pays`).

use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

use crate::geom::Point;

/// One site in the triangulation, with its index in the caller's slice.
#[derive(Clone, Copy, Debug)]
struct Site {
    position: Point2<f64>,
    index: usize,
}

impl HasPosition for Site {
    type Scalar = f64;

    fn position(&self) -> Point2<f64> {
        self.position
    }
}

/// The Delaunay graph of a set of sites, as sorted neighbour lists by index.
#[derive(Clone, Debug, Default)]
pub(super) struct SiteGraph {
    /// `neighbors[offsets[i]..offsets[i + 1]]` are site `i`'s neighbours, sorted.
    offsets: Vec<usize>,
    neighbors: Vec<usize>,
}

impl SiteGraph {
    /// The Delaunay graph of `points`. Sites at the same spot share their
    /// neighbours and neighbour each other; collinear sites form a path;
    /// fewer than two usable sites, no edges. A site spade cannot take
    /// (not finite, or beyond its range) has no neighbours.
    pub(super) fn new(points: &[Point]) -> Self {
        let n = points.len();
        let sites: Vec<Site> = points
            .iter()
            .enumerate()
            .filter_map(|(index, p)| {
                let position = spade::mitigate_underflow(Point2::new(p.x, p.y));
                spade::validate_coordinate(position.x)
                    .and(spade::validate_coordinate(position.y))
                    .ok()
                    .map(|()| Site { position, index })
            })
            .collect();
        let mut lists: Vec<Vec<usize>> = vec![Vec::new(); n];
        // Every coordinate was validated, so loading cannot fail; an error
        // would leave the graph without edges, which only costs candidates.
        if let Ok(tri) = DelaunayTriangulation::<Site>::bulk_load(sites.clone()) {
            for e in tri.undirected_edges() {
                let [u, v] = e.vertices();
                let (u, v) = (u.data().index, v.data().index);
                lists[u].push(v);
                lists[v].push(u);
            }
            // Duplicates: spade keeps one site per spot; the others take its
            // neighbours and the two neighbour each other.
            if tri.num_vertices() < sites.len() {
                let mut kept = vec![false; n];
                for v in tri.vertices() {
                    kept[v.data().index] = true;
                }
                for s in sites.iter().filter(|s| !kept[s.index]) {
                    if let Some(v) = tri.locate_vertex(s.position) {
                        let rep = v.data().index;
                        let shared = lists[rep].clone();
                        lists[s.index].extend(shared);
                        lists[s.index].push(rep);
                        lists[rep].push(s.index);
                    }
                }
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut neighbors = Vec::new();
        offsets.push(0);
        for mut l in lists {
            l.sort_unstable();
            l.dedup();
            neighbors.extend(l);
            offsets.push(neighbors.len());
        }
        Self { offsets, neighbors }
    }

    /// The sorted neighbours of site `i` (empty beyond the graph).
    pub(super) fn neighbors(&self, i: usize) -> &[usize] {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&s), Some(&e)) => &self.neighbors[s..e],
            _ => &[],
        }
    }

    /// True when sites `i` and `j` are Delaunay neighbours.
    pub(super) fn are_adjacent(&self, i: usize, j: usize) -> bool {
        self.neighbors(i).binary_search(&j).is_ok()
    }

    /// The edges `(c, d)` whose one flip would make `a`–`b` an edge: `c` and
    /// `d` neighbour both and each other, and the segment `a`–`b` crosses
    /// `c`–`d` (so `a c b d` is the convex quadrilateral of two triangles of
    /// the triangulation). Empty when `a` and `b` already neighbour or are
    /// further apart than one flip.
    pub(super) fn one_flip(&self, points: &[Point], a: usize, b: usize) -> Vec<(usize, usize)> {
        if self.are_adjacent(a, b) {
            return Vec::new();
        }
        let (na, nb) = (self.neighbors(a), self.neighbors(b));
        let common: Vec<usize> = na
            .iter()
            .copied()
            .filter(|c| nb.binary_search(c).is_ok())
            .collect();
        let mut out = Vec::new();
        for (i, &c) in common.iter().enumerate() {
            for &d in &common[i + 1..] {
                if self.are_adjacent(c, d) && crosses(points[a], points[b], points[c], points[d]) {
                    out.push((c, d));
                }
            }
        }
        out
    }
}

/// True when the open segments `p`–`q` and `r`–`s` cross properly.
fn crosses(p: Point, q: Point, r: Point, s: Point) -> bool {
    let side = |a: Point, b: Point, c: Point| (b - a).perp_dot(c - a);
    let (d1, d2) = (side(p, q, r), side(p, q, s));
    let (d3, d4) = (side(r, s, p), side(r, s, q));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y)
    }

    #[test]
    fn a_square_with_its_centre_is_a_wheel() {
        let pts = [p(0.0, 0.0), p(2.0, 0.0), p(2.0, 2.0), p(0.0, 2.0), p(1.0, 1.0)];
        let g = SiteGraph::new(&pts);
        assert_eq!(g.neighbors(4), &[0, 1, 2, 3]);
        // The rim is a cycle; opposite corners are not neighbours.
        assert!(g.are_adjacent(0, 1) && g.are_adjacent(1, 2) && g.are_adjacent(2, 3));
        assert!(!g.are_adjacent(0, 2) && !g.are_adjacent(1, 3));
    }

    #[test]
    fn tiny_collinear_and_duplicate_sites_are_safe() {
        assert!(SiteGraph::new(&[]).neighbors(0).is_empty());
        let one = SiteGraph::new(&[p(1.0, 1.0)]);
        assert!(one.neighbors(0).is_empty());
        let two = SiteGraph::new(&[p(0.0, 0.0), p(1.0, 0.0)]);
        assert_eq!(two.neighbors(0), &[1]);
        // Collinear: a path, not a triangle fan.
        let line = SiteGraph::new(&[p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0)]);
        assert_eq!(line.neighbors(2), &[0, 1]);
        assert!(!line.are_adjacent(0, 1));
        // A duplicate shares its twin's neighbours and neighbours it.
        let dup = SiteGraph::new(&[p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0), p(1.0, 0.0)]);
        assert!(dup.are_adjacent(1, 3) && dup.are_adjacent(3, 1));
        assert!(dup.are_adjacent(3, 0) && dup.are_adjacent(3, 2));
        // Not finite: no neighbours, and the others still triangulate.
        let nan = SiteGraph::new(&[p(f64::NAN, 0.0), p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)]);
        assert!(nan.neighbors(0).is_empty());
        assert_eq!(nan.neighbors(1), &[2, 3]);
    }

    #[test]
    fn one_flip_finds_the_edge_between_two_opposite_corners() {
        // A rhombus, long across 0-2: the Delaunay diagonal is 1-3, and one
        // flip of it would join 0 and 2.
        let pts = [p(0.0, 0.0), p(2.0, -0.5), p(4.0, 0.0), p(2.0, 0.5)];
        let g = SiteGraph::new(&pts);
        assert!(g.are_adjacent(1, 3));
        assert_eq!(g.one_flip(&pts, 0, 2), vec![(1, 3)]);
        assert!(g.one_flip(&pts, 1, 3).is_empty());
    }
}
