//! The per-cell kernel: a convex polygon whose edges carry labels, clipped by
//! power-bisector half-planes. Owns the bisector and dominance predicates; may not
//! touch the grid, the diagram assembly or anything outside `src/power/`.
//!
//! All coordinates here are *local*: relative to the site whose cell is being
//! built. Working relative to `p_i` keeps the bisector offset small (it is
//! `|d|² − w_j + w_i` instead of `|p_j|² − |p_i|² − …`), which avoids the
//! cancellation that absolute coordinates far from the origin would cause.

use crate::geom::Point;

/// Edge label for a piece of the clip polygon's boundary.
pub(crate) const CLIP_EDGE: usize = usize::MAX;

/// True when site `j` (weight `wj`, squared distance `d2` from site `i`) makes
/// `p_i` lie strictly outside cell `i`.
///
/// `wj − wi > d2` says the half-plane of `j` strictly excludes `p_i`. When the
/// sites coincide (`d2 == 0`, which includes a distance so small that its square
/// underflows) the bisector is undefined; with equal weights the lower index wins
/// the whole shared region, so a coincident lower-index site of equal weight also
/// dominates.
#[inline]
pub(crate) fn dominates(j: usize, wj: f64, i: usize, wi: f64, d2: f64) -> bool {
    wj - wi > d2 || (d2 == 0.0 && wj == wi && j < i)
}

/// What one clipping step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ClipOutcome {
    /// The half-plane contained the whole cell (or could not be evaluated).
    Unchanged,
    /// Part of the cell was cut away; the cell still has area.
    Cut,
    /// Nothing with area is left.
    Empty,
}

/// A convex, positively oriented polygon in local coordinates; `labels[k]` names
/// what produced the edge from `verts[k]` to `verts[k + 1]` (a site index or
/// [`CLIP_EDGE`]). Holds its own scratch buffers so clipping allocates only
/// while a cell grows beyond every earlier cell.
#[derive(Clone, Debug, Default)]
pub(crate) struct LabeledPolygon {
    /// Vertices, positively oriented, relative to the cell's site.
    pub(crate) verts: Vec<Point>,
    /// One label per edge, same indexing as `verts`.
    pub(crate) labels: Vec<usize>,
    /// Largest squared distance from the local origin (the site) to a vertex.
    pub(crate) r2: f64,
    /// False until a clip has removed something: an uncut cell is the clip
    /// polygon itself and is returned bit for bit.
    pub(crate) cut: bool,
    side: Vec<f64>,
    out_verts: Vec<Point>,
    out_labels: Vec<usize>,
}

impl LabeledPolygon {
    /// Resets to `clip` translated by `-origin`, every edge labelled as clip boundary.
    pub(crate) fn reset(&mut self, clip: &[Point], origin: Point) {
        self.verts.clear();
        self.labels.clear();
        self.verts.extend(clip.iter().map(|p| *p - origin));
        self.labels
            .extend(std::iter::repeat_n(CLIP_EDGE, clip.len()));
        self.r2 = max_r2(&self.verts);
        self.cut = false;
    }

    /// True when no area is left.
    pub(crate) fn is_empty(&self) -> bool {
        self.verts.len() < 3
    }

    /// Marks the polygon empty.
    pub(crate) fn clear(&mut self) {
        self.verts.clear();
        self.labels.clear();
        self.r2 = 0.0;
    }

    /// Keeps the part where `normal · x <= offset`; the new edge gets `label`.
    ///
    /// Sutherland–Hodgman on one half-plane. A vertex with side exactly zero
    /// counts as inside and no intersection is made next to it, so no duplicate
    /// vertices appear from exact hits. A half-plane whose side values are not
    /// all numbers (overflow on absurd inputs) is ignored rather than trusted.
    pub(crate) fn clip(&mut self, normal: Point, offset: f64, label: usize) -> ClipOutcome {
        if self.is_empty() {
            return ClipOutcome::Empty;
        }
        self.side.clear();
        let mut any_out = false;
        let mut any_in = false;
        for v in &self.verts {
            let s = normal.dot(*v) - offset;
            if s.is_nan() {
                return ClipOutcome::Unchanged;
            }
            any_out |= s > 0.0;
            any_in |= s < 0.0;
            self.side.push(s);
        }
        if !any_out {
            return ClipOutcome::Unchanged;
        }
        if !any_in {
            // Everything is outside or on the line: at most a segment remains.
            self.clear();
            return ClipOutcome::Empty;
        }
        let n = self.verts.len();
        self.out_verts.clear();
        self.out_labels.clear();
        for k in 0..n {
            let k1 = if k + 1 == n { 0 } else { k + 1 };
            let (p, q) = (self.verts[k], self.verts[k1]);
            let (sp, sq) = (self.side[k], self.side[k1]);
            let lab = self.labels[k];
            if sp <= 0.0 {
                if sq > 0.0 {
                    // Leaving: the edge from here on runs along the new line.
                    if sp == 0.0 {
                        self.out_verts.push(p);
                        self.out_labels.push(label);
                    } else {
                        self.out_verts.push(p);
                        self.out_labels.push(lab);
                        self.out_verts.push(p + (q - p) * (sp / (sp - sq)));
                        self.out_labels.push(label);
                    }
                } else {
                    self.out_verts.push(p);
                    self.out_labels.push(lab);
                }
            } else if sq < 0.0 {
                // Entering: the rest of edge `k` survives from the crossing on.
                self.out_verts.push(p + (q - p) * (sp / (sp - sq)));
                self.out_labels.push(lab);
            }
        }
        std::mem::swap(&mut self.verts, &mut self.out_verts);
        std::mem::swap(&mut self.labels, &mut self.out_labels);
        if self.verts.len() < 3 || local_twice_area(&self.verts) <= 0.0 {
            self.clear();
            return ClipOutcome::Empty;
        }
        self.r2 = max_r2(&self.verts);
        self.cut = true;
        ClipOutcome::Cut
    }

    /// Clips by the power bisector of the local site `i` (weight `wi`) against
    /// site `j` at offset `d = p_j − p_i` with weight `wj`: keeps
    /// `{x : |x|² − wi ≤ |x − d|² − wj}`, i.e. `2 d·x ≤ |d|² − wj + wi`.
    /// Coincident sites (`|d|² == 0`) follow the rule of [`dominates`]: the
    /// dominated one loses everything, the other is untouched.
    pub(crate) fn clip_by_site(
        &mut self,
        i: usize,
        wi: f64,
        j: usize,
        wj: f64,
        d: Point,
        d2: f64,
    ) -> ClipOutcome {
        if d2 == 0.0 {
            if dominates(j, wj, i, wi, d2) {
                self.clear();
                return ClipOutcome::Empty;
            }
            return ClipOutcome::Unchanged;
        }
        self.clip(2.0 * d, d2 - wj + wi, j)
    }
}

/// Largest squared distance from the origin to a vertex.
fn max_r2(verts: &[Point]) -> f64 {
    verts.iter().map(|v| v.length_squared()).fold(0.0, f64::max)
}

/// Twice the signed area (shoelace about the first vertex).
pub(crate) fn local_twice_area(verts: &[Point]) -> f64 {
    let Some(&o) = verts.first() else {
        return 0.0;
    };
    verts
        .windows(2)
        .skip(1)
        .map(|w| crate::geom::cross(w[0] - o, w[1] - o))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square() -> LabeledPolygon {
        let mut p = LabeledPolygon::default();
        let sq = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(0.0, 1.0),
        ];
        p.reset(&sq, Point::ZERO);
        p
    }

    #[test]
    fn cut_labels_the_new_edge() {
        let mut p = unit_square();
        assert_eq!(p.clip(Point::X, 0.5, 7), ClipOutcome::Cut);
        assert_eq!(p.verts.len(), 4);
        assert!((local_twice_area(&p.verts) - 1.0).abs() < 1e-15);
        // Exactly one edge is labelled 7 and it is the vertical line x = 0.5.
        let sevens: Vec<usize> = (0..4).filter(|&k| p.labels[k] == 7).collect();
        assert_eq!(sevens.len(), 1);
        let k = sevens[0];
        assert_eq!(p.verts[k].x, 0.5);
        assert_eq!(p.verts[(k + 1) % 4].x, 0.5);
        assert_eq!(p.labels.iter().filter(|&&l| l == CLIP_EDGE).count(), 3);
    }

    #[test]
    fn cut_through_vertices_keeps_labels_consistent() {
        let mut p = unit_square();
        // The diagonal x + y <= 1 passes exactly through two vertices.
        assert_eq!(p.clip(Point::new(1.0, 1.0), 1.0, 3), ClipOutcome::Cut);
        assert_eq!(p.verts.len(), 3);
        assert_eq!(p.labels.iter().filter(|&&l| l == 3).count(), 1);
        assert!((local_twice_area(&p.verts) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn whole_and_nothing() {
        let mut p = unit_square();
        assert_eq!(p.clip(Point::X, 2.0, 1), ClipOutcome::Unchanged);
        assert_eq!(p.clip(Point::X, 0.0, 1), ClipOutcome::Empty);
        assert!(p.is_empty());
        assert_eq!(p.clip(Point::X, 5.0, 1), ClipOutcome::Empty);
    }

    #[test]
    fn coincident_sites_follow_the_tie_rule() {
        let mut p = unit_square();
        // Equal weights: the higher index loses, the lower keeps everything.
        assert_eq!(
            p.clip_by_site(0, 1.0, 1, 1.0, Point::ZERO, 0.0),
            ClipOutcome::Unchanged
        );
        assert_eq!(
            p.clip_by_site(1, 1.0, 0, 1.0, Point::ZERO, 0.0),
            ClipOutcome::Empty
        );
        let mut p = unit_square();
        assert_eq!(
            p.clip_by_site(0, 1.0, 1, 2.0, Point::ZERO, 0.0),
            ClipOutcome::Empty
        );
        assert!(dominates(1, 2.0, 0, 1.0, 0.0));
        assert!(!dominates(1, 1.0, 0, 1.0, 0.0));
        assert!(dominates(0, 1.0, 1, 1.0, 0.0));
    }
}
