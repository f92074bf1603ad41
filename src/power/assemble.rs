//! Shared by the fast and naive paths: the per-site inputs, the state of one cell
//! under construction, turning it into a [`Cell`], and making the neighbour
//! relation exactly symmetric. May not decide which sites to visit (that is the
//! caller's job) and does no clipping arithmetic of its own beyond
//! [`LabelledPolygon`].

use rayon::prelude::*;

use super::clip::{dominates, ClipOutcome, LabeledPolygon, CLIP_EDGE};
use super::{Cell, Neighbor, Site};
use crate::geom::{ConvexPolygon, Point};

/// Shared edges shorter than this fraction of the clip's diameter are dropped:
/// far below anything visible, far above the round-off of one clipping step.
const EDGE_TOL_REL: f64 = 1e-9;

/// The sites split into flat arrays, plus which of them take part.
pub(crate) struct Prepared<'a> {
    pub(crate) pos: Vec<Point>,
    pub(crate) w: Vec<f64>,
    /// `Some(k)` for a site sitting exactly on site `k` that dominates it (the
    /// heaviest of the coincident group, lowest index on ties).
    pub(crate) shadow: Vec<Option<usize>>,
    /// Finite position and weight, and not shadowed: the sites whose bisectors
    /// are clipped with. A site with a NaN or infinite coordinate or weight is
    /// ignored entirely.
    pub(crate) active: Vec<bool>,
    pub(crate) clip: &'a ConvexPolygon,
    /// Minimum length of a reported shared edge.
    pub(crate) edge_tol: f64,
}

impl<'a> Prepared<'a> {
    pub(crate) fn new(sites: &[Site], clip: &'a ConvexPolygon) -> Self {
        let usable: Vec<bool> = sites
            .iter()
            .map(|s| s.position.is_finite() && s.weight.is_finite())
            .collect();
        let shadow = shadows(sites, &usable);
        let active = usable
            .iter()
            .zip(&shadow)
            .map(|(u, s)| *u && s.is_none())
            .collect();
        Prepared {
            pos: sites.iter().map(|s| s.position).collect(),
            w: sites.iter().map(|s| s.weight).collect(),
            shadow,
            active,
            clip,
            edge_tol: EDGE_TOL_REL * clip.diameter_bound(),
        }
    }

    /// Number of sites.
    pub(crate) fn len(&self) -> usize {
        self.pos.len()
    }
}

/// For each site lying exactly on another usable site, the one that wins their
/// shared region: the highest weight, then the lowest index.
///
/// The losers are taken out of all clipping. Their half-planes are never
/// tighter than the winner's (same bisector direction, no larger weight), so
/// this changes no cell; but it stops identical bisectors from competing for
/// the same edge label, which round-off would decide arbitrarily.
fn shadows(sites: &[Site], usable: &[bool]) -> Vec<Option<usize>> {
    // `+ 0.0` turns −0.0 into 0.0 so that equal coordinates sort together.
    let key = |k: usize| (sites[k].position.x + 0.0, sites[k].position.y + 0.0);
    let mut order: Vec<usize> = (0..sites.len()).filter(|&k| usable[k]).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(a.cmp(&b))
    });
    let mut shadow = vec![None; sites.len()];
    for group in order.chunk_by(|&a, &b| key(a) == key(b)) {
        let winner = group.iter().copied().fold(group[0], |best, k| {
            if sites[k].weight > sites[best].weight {
                k
            } else {
                best
            }
        });
        for &k in group.iter().filter(|&&k| k != winner) {
            shadow[k] = Some(winner);
        }
    }
    shadow
}

/// One cell under construction: the polygon so far and the nearest dominating
/// site seen so far.
pub(crate) struct CellBuilder {
    pub(crate) poly: LabeledPolygon,
    i: usize,
    p: Point,
    wi: f64,
    /// `(squared distance, index)` of the nearest dominating site seen.
    pub(crate) best: Option<(f64, usize)>,
}

impl CellBuilder {
    pub(crate) fn new(poly: LabeledPolygon) -> Self {
        CellBuilder {
            poly,
            i: 0,
            p: Point::ZERO,
            wi: 0.0,
            best: None,
        }
    }

    /// Starts cell `i` from the whole clip polygon.
    pub(crate) fn start(&mut self, input: &Prepared<'_>, i: usize) {
        self.i = i;
        self.p = input.pos[i];
        self.wi = input.w[i];
        self.best = None;
        self.poly.reset(input.clip.points(), self.p);
    }

    /// Weight of the site being built.
    pub(crate) fn weight(&self) -> f64 {
        self.wi
    }

    /// Position of the site being built.
    pub(crate) fn position(&self) -> Point {
        self.p
    }

    /// Takes site `j` into account: records it if it dominates, and clips by its
    /// bisector unless the cell is empty or (with `may_skip`) the security-radius
    /// test proves the bisector cannot cut the cell.
    #[inline]
    pub(crate) fn visit(&mut self, j: usize, pj: Point, wj: f64, may_skip: bool) {
        let d = pj - self.p;
        let d2 = d.length_squared();
        if dominates(j, wj, self.i, self.wi, d2)
            && self.best.is_none_or(|(bd2, bj)| (d2, j) < (bd2, bj))
        {
            self.best = Some((d2, j));
        }
        if self.poly.is_empty() || (may_skip && cannot_cut(d2, wj, self.poly.r2, self.wi)) {
            return;
        }
        let _: ClipOutcome = self.poly.clip_by_site(self.i, self.wi, j, wj, d, d2);
    }

    /// Turns the finished state into a [`Cell`] (neighbours not yet symmetric).
    pub(crate) fn finish(&self, clip: &ConvexPolygon, edge_tol: f64) -> Cell {
        let dominated_by = self.best.map(|(_, j)| j);
        if self.poly.is_empty() {
            return empty_cell(self.p, dominated_by);
        }
        if !self.poly.cut {
            // Translating there and back would perturb the last bits.
            return Cell {
                polygon: Some(clip.clone()),
                area: clip.area(),
                centroid: clip.centroid(),
                neighbors: Vec::new(),
                dominated_by,
            };
        }
        let verts: Vec<Point> = self.poly.verts.iter().map(|v| *v + self.p).collect();
        let Some(polygon) = ConvexPolygon::from_convex(verts.clone()) else {
            return empty_cell(self.p, dominated_by);
        };
        let m = verts.len();
        let mut edges: Vec<(usize, f64, [Point; 2])> = (0..m)
            .filter(|&k| self.poly.labels[k] != CLIP_EDGE)
            .map(|k| {
                let (a, b) = (verts[k], verts[(k + 1) % m]);
                (self.poly.labels[k], a.distance(b), [a, b])
            })
            .filter(|e| e.1 >= edge_tol)
            .collect();
        // Round-off can leave a label on a second, tiny edge; keep the longest
        // (first on ties, which is deterministic since the vertex order is).
        edges.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        edges.dedup_by_key(|e| e.0);
        let neighbors = edges
            .into_iter()
            .map(|(site, _, edge)| Neighbor { site, edge })
            .collect();
        Cell {
            area: polygon.area(),
            centroid: polygon.centroid(),
            polygon: Some(polygon),
            neighbors,
            dominated_by,
        }
    }
}

/// The security-radius test. Every vertex `v` of the current cell has
/// `|v − p_i| ≤ R` (R² = `r2`), and the cell is the convex hull of its vertices.
/// If site `j` is at distance `d ≥ R` then `|v − p_j| ≥ d − R ≥ 0`, so
/// `|v − p_j|² − w_j ≥ (d − R)² − w_j`; if that bound is at least
/// `R² − w_i ≥ |v − p_i|² − w_i`, every vertex lies in `j`'s half-plane for `i`,
/// and so does the whole (convex) cell: `j` cannot cut it. The same inequality
/// gives `w_j − w_i ≤ d² − 2dR ≤ d²`, so such a `j` never dominates `i` either.
/// Used per site with its own `d` and `w_j`, and per grid node with the node's
/// distance lower bound and largest weight (the test is monotone in both).
#[inline]
pub(crate) fn cannot_cut(d2: f64, wj: f64, r2: f64, wi: f64) -> bool {
    if d2 < r2 {
        return false;
    }
    let gap = d2.sqrt() - r2.sqrt();
    gap * gap - wj >= r2 - wi
}

/// The cell of a site that owns no area.
pub(crate) fn empty_cell(position: Point, dominated_by: Option<usize>) -> Cell {
    Cell {
        polygon: None,
        area: 0.0,
        centroid: position,
        neighbors: Vec::new(),
        dominated_by,
    }
}

/// Makes the neighbour relation exactly symmetric. Edges pointing at an empty
/// cell are dropped (a vanished sliver can still leave a labelled edge on its
/// neighbour); then, when `i` lists `j` but `j` does not list `i` (its copy of
/// the edge fell below the length tolerance), `j` gets `i`'s edge, reversed to
/// follow `j`'s orientation.
pub(crate) fn symmetrize(cells: &mut [Cell], parallel: bool) {
    let nonempty: Vec<bool> = cells.iter().map(|c| c.polygon.is_some()).collect();
    let keep_live = |c: &mut Cell| {
        c.neighbors
            .retain(|nb| nonempty.get(nb.site).copied().unwrap_or(false));
    };
    if parallel {
        cells.par_iter_mut().for_each(keep_live);
    } else {
        cells.iter_mut().for_each(keep_live);
    }
    let missing = |(i, c): (usize, &Cell)| -> Vec<(usize, Neighbor)> {
        c.neighbors
            .iter()
            .filter(|nb| {
                cells[nb.site]
                    .neighbors
                    .binary_search_by_key(&i, |x| x.site)
                    .is_err()
            })
            .map(|nb| {
                (
                    nb.site,
                    Neighbor {
                        site: i,
                        edge: [nb.edge[1], nb.edge[0]],
                    },
                )
            })
            .collect()
    };
    // Collected in site order either way, so the result does not depend on
    // `parallel`.
    let additions: Vec<(usize, Neighbor)> = if parallel {
        cells
            .par_iter()
            .enumerate()
            .flat_map_iter(missing)
            .collect()
    } else {
        cells.iter().enumerate().flat_map(missing).collect()
    };
    for (j, nb) in additions {
        let list = &mut cells[j].neighbors;
        if let Err(at) = list.binary_search_by_key(&nb.site, |x| x.site) {
            list.insert(at, nb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn security_radius_test_is_exact_at_the_boundary() {
        // Cell within radius 1 of p_i, equal weights: a site at distance 2 has its
        // bisector at distance 1, touching but not cutting.
        assert!(cannot_cut(4.0, 0.0, 1.0, 0.0));
        assert!(!cannot_cut(3.9, 0.0, 1.0, 0.0));
        // A heavier far site can still cut.
        assert!(!cannot_cut(4.0, 0.5, 1.0, 0.0));
        // Closer than R: never skipped.
        assert!(!cannot_cut(0.25, -100.0, 1.0, 0.0));
    }

    #[test]
    fn symmetrize_adds_the_missing_side() {
        let p = |x: f64, y: f64| Point::new(x, y);
        let sq = ConvexPolygon::rectangle(0.0, 0.0, 1.0, 1.0).ok();
        let mk = |nbs: Vec<Neighbor>| Cell {
            polygon: sq.clone(),
            area: 1.0,
            centroid: p(0.5, 0.5),
            neighbors: nbs,
            dominated_by: None,
        };
        let mut cells = vec![
            mk(vec![Neighbor {
                site: 1,
                edge: [p(1.0, 0.0), p(1.0, 1.0)],
            }]),
            mk(vec![]),
            empty_cell(p(0.0, 0.0), Some(0)),
        ];
        cells[1].neighbors.push(Neighbor {
            site: 2,
            edge: [p(0.0, 0.0), p(1.0, 0.0)],
        });
        symmetrize(&mut cells, false);
        assert_eq!(cells[1].neighbors.len(), 1);
        assert_eq!(cells[1].neighbors[0].site, 0);
        assert_eq!(cells[1].neighbors[0].edge, [p(1.0, 1.0), p(1.0, 0.0)]);
    }
}
