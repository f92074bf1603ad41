//! Power diagrams: weighted sites clipped to a convex polygon, with each cell's
//! neighbours and shared edges. Owns everything under `src/power/`; uses
//! [`crate::geom`] and may not touch layout, rendering or I/O.
//!
//! Catalog:
//! - [`power_diagram`] (in `fast`): the production path, cell-by-cell clipping
//!   with a security-radius stop over a bucket grid, parallel for large inputs.
//! - [`power_diagram_naive`] (in `naive`): the O(n²) reference used by tests.
//! - [`PowerDiagram::sanity_check`] (in `check`): invariants every diagram must meet.
//! - `clip`: the labelled half-plane clipping kernel and the dominance rule.
//! - `grid`: bucket grid plus max-weight pyramid for the fast path.
//! - `assemble`: per-cell state, output cells, neighbour symmetry.

mod assemble;
// Invariant checks of a diagram, for the tests and the repository's tools.
#[cfg(any(test, feature = "internals"))]
mod check;
mod clip;
mod fast;
mod grid;
#[cfg(test)]
mod naive;
#[cfg(test)]
mod proptests;

pub use fast::power_diagram;
#[cfg(test)]
pub(crate) use naive::power_diagram_naive;

use crate::geom::ConvexPolygon;
use crate::geom::Point;

/// A weighted site. Its cell is `{x : |x − p|² − w ≤ |x − p_j|² − w_j for all j}`:
/// a larger weight grows the cell. Only weight differences matter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// Position; may lie outside the clip polygon.
    pub position: Point,
    /// Power weight (a squared length).
    pub weight: f64,
}

/// A power diagram clipped to a convex polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerDiagram {
    /// One cell per site, in site order.
    pub cells: Vec<Cell>,
}

/// The cell of one site.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// The region, or `None` when the site owns no area.
    pub polygon: Option<ConvexPolygon>,
    /// Area of `polygon`; 0 when empty.
    pub area: f64,
    /// Area centroid of `polygon`; the site's position when empty.
    pub centroid: Point,
    /// Adjacent cells, sorted by site index; the relation is symmetric.
    pub neighbors: Vec<Neighbor>,
    /// `Some(j)` when the site's own position lies strictly outside its cell
    /// because `w_j − w_i > |p_i − p_j|²` (or `j` is a coincident site of equal
    /// weight and lower index); `j` is the nearest such site, the lowest index
    /// on ties, except that a site sitting exactly on a heavier (or equally
    /// heavy, lower-index) site is never named: the site it sits on is.
    /// `None` otherwise.
    pub dominated_by: Option<usize>,
}

/// One shared boundary segment between two cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Index of the adjacent site.
    pub site: usize,
    /// The shared segment, in the orientation of the cell that lists it (its
    /// length exceeds a tolerance of 1e-9 × the clip's diameter).
    pub edge: [Point; 2],
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> ConvexPolygon {
        ConvexPolygon::rectangle(0.0, 0.0, 4.0, 4.0).expect("square")
    }

    fn site(x: f64, y: f64, w: f64) -> Site {
        Site {
            position: Point::new(x, y),
            weight: w,
        }
    }

    fn both(sites: &[Site], clip: &ConvexPolygon) -> [PowerDiagram; 2] {
        let fast = power_diagram(sites, clip);
        let naive = power_diagram_naive(sites, clip);
        fast.sanity_check(sites, clip).expect("fast diagram sane");
        naive.sanity_check(sites, clip).expect("naive diagram sane");
        [fast, naive]
    }

    #[test]
    fn two_equal_sites_split_at_the_bisector() {
        let sites = [site(1.0, 2.0, 0.0), site(3.0, 2.0, 0.0)];
        for d in both(&sites, &square()) {
            assert!((d.cells[0].area - 8.0).abs() < 1e-12);
            assert!((d.cells[1].area - 8.0).abs() < 1e-12);
            let e = d.cells[0].neighbors[0].edge;
            assert_eq!(d.cells[0].neighbors[0].site, 1);
            assert!((e[0].x - 2.0).abs() < 1e-12 && (e[1].x - 2.0).abs() < 1e-12);
            assert!((e[0] - e[1]).length() > 3.999);
            assert_eq!(d.cells[1].neighbors[0].site, 0);
            assert_eq!(d.cells[0].dominated_by, None);
        }
    }

    #[test]
    fn weight_difference_moves_the_bisector() {
        // Distance 2, w_0 − w_1 = 1: the line moves (w_i − w_j)/(2d) = 0.25
        // towards site 1.
        let sites = [site(1.0, 2.0, 1.0), site(3.0, 2.0, 0.0)];
        for d in both(&sites, &square()) {
            assert!((d.cells[0].area - 4.0 * 2.25).abs() < 1e-12);
            assert!((d.cells[1].area - 4.0 * 1.75).abs() < 1e-12);
            for x in d.cells[0].neighbors[0].edge {
                assert!((x.x - 2.25).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn three_sites() {
        // Equal weights at (1,1), (3,1), (2,3): cells meet at the circumcentre
        // (2, 1.75).
        let sites = [
            site(1.0, 1.0, 0.0),
            site(3.0, 1.0, 0.0),
            site(2.0, 3.0, 0.0),
        ];
        for d in both(&sites, &square()) {
            let total: f64 = d.cells.iter().map(|c| c.area).sum();
            assert!((total - 16.0).abs() < 1e-12);
            // Symmetry about x = 2.
            assert!((d.cells[0].area - d.cells[1].area).abs() < 1e-12);
            for c in &d.cells {
                assert_eq!(c.neighbors.len(), 2);
            }
            let hits = d.cells[2]
                .polygon
                .as_ref()
                .expect("cell 2")
                .points()
                .iter()
                .filter(|v| (**v - Point::new(2.0, 1.75)).length() < 1e-12)
                .count();
            assert_eq!(hits, 1);
        }
    }

    #[test]
    fn dominated_site_is_empty() {
        // Site 1 is 0.5 from site 0, and w_0 − w_1 = 10 > 0.25.
        let sites = [
            site(2.0, 2.0, 10.0),
            site(2.5, 2.0, 0.0),
            site(3.9, 3.9, 0.0),
        ];
        for d in both(&sites, &square()) {
            assert_eq!(d.cells[1].polygon, None);
            assert_eq!(d.cells[1].area, 0.0);
            assert_eq!(d.cells[1].centroid, sites[1].position);
            assert_eq!(d.cells[1].dominated_by, Some(0));
            assert!(d.cells[1].neighbors.is_empty());
            assert!(d.cells[0].neighbors.iter().all(|nb| nb.site != 1));
        }
    }

    #[test]
    fn single_site_gets_the_clip() {
        let clip = ConvexPolygon::regular(Point::new(1.0, 1.0), 2.0, 7).expect("heptagon");
        let sites = [site(10.0, 10.0, 3.0)];
        for d in both(&sites, &clip) {
            assert_eq!(d.cells[0].polygon.as_ref(), Some(&clip));
            assert!(d.cells[0].neighbors.is_empty());
        }
    }

    #[test]
    fn no_sites_no_cells() {
        let d = power_diagram(&[], &square());
        assert!(d.cells.is_empty());
        d.sanity_check(&[], &square()).expect("sane");
    }

    #[test]
    fn coincident_sites() {
        let sites = [
            site(1.0, 1.0, 0.0),
            site(1.0, 1.0, 0.0),
            site(1.0, 1.0, 0.5),
            site(3.0, 3.0, 0.0),
        ];
        for d in both(&sites, &square()) {
            // The heavier of the three coincident sites wins; the two lighter
            // ones are dominated by it.
            assert!(d.cells[2].polygon.is_some());
            assert_eq!(d.cells[0].dominated_by, Some(2));
            assert_eq!(d.cells[1].dominated_by, Some(2));
            assert_eq!(d.cells[0].polygon, None);
            assert_eq!(d.cells[1].polygon, None);
        }
        let equal = [
            site(1.0, 1.0, 0.0),
            site(1.0, 1.0, 0.0),
            site(1.0, 1.0, 0.0),
        ];
        for d in both(&equal, &square()) {
            assert!((d.cells[0].area - 16.0).abs() < 1e-12);
            assert_eq!(d.cells[1].dominated_by, Some(0));
            assert_eq!(d.cells[2].dominated_by, Some(0));
        }
    }

    #[test]
    fn non_finite_sites_are_ignored() {
        let sites = [
            site(1.0, 1.0, 0.0),
            site(f64::NAN, 1.0, 0.0),
            site(3.0, 3.0, f64::INFINITY),
        ];
        for d in both(&sites, &square()) {
            assert!((d.cells[0].area - 16.0).abs() < 1e-12);
            assert_eq!(d.cells[1].polygon, None);
            assert_eq!(d.cells[2].polygon, None);
            assert_eq!(d.cells[2].dominated_by, None);
        }
    }

    #[test]
    fn collinear_sites_make_strips() {
        let sites: Vec<Site> = (0..40)
            .map(|k| site(0.05 + 0.1 * k as f64, 2.0, 0.0))
            .collect();
        for d in both(&sites, &square()) {
            for (k, c) in d.cells.iter().enumerate() {
                assert!((c.area - 0.4).abs() < 1e-9, "cell {k}: {}", c.area);
                let expect = if k == 0 || k == 39 { 1 } else { 2 };
                assert_eq!(c.neighbors.len(), expect);
            }
        }
    }

    #[test]
    fn huge_weight_ratio() {
        // A centre site squeezed by four heavy neighbours 500 away: its cell is
        // the square of half-width (d² + w_c − w)/(2d) = 0.5, area 1, next to
        // cells of about 10^6.
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 2000.0, 2000.0).expect("clip");
        let sites = [
            site(1000.0, 1000.0, -249_500.0),
            site(1500.0, 1000.0, 0.0),
            site(500.0, 1000.0, 0.0),
            site(1000.0, 1500.0, 0.0),
            site(1000.0, 500.0, 0.0),
        ];
        for d in both(&sites, &clip) {
            assert!((d.cells[0].area - 1.0).abs() < 1e-9, "{}", d.cells[0].area);
            assert_eq!(d.cells[0].neighbors.len(), 4);
            assert!(
                (d.cells[1].area - 999_999.75).abs() < 1e-6,
                "{}",
                d.cells[1].area
            );
        }
    }

    /// SplitMix64 in [0, 1), for seeded test inputs.
    fn rng(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn many_sites_tile_the_clip() {
        let clip = ConvexPolygon::regular(Point::new(0.0, 0.0), 100.0, 11).expect("clip");
        let mut next = rng(7);
        let n = 12_000;
        let sites: Vec<Site> = (0..n)
            .map(|_| Site {
                position: clip.sample(next(), next()),
                weight: 2.0 * next(),
            })
            .collect();
        let d = power_diagram(&sites, &clip);
        d.sanity_check(&sites, &clip).expect("sane");
    }

    #[test]
    fn long_line_of_sites_stays_cheap_and_correct() {
        // Strip cells have a circumscribed circle far larger than the cell;
        // the vertex-wise box test keeps this near linear.
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 100.0, 100.0).expect("clip");
        let n = 10_000;
        let sites: Vec<Site> = (0..n)
            .map(|k| site((k as f64 + 0.5) * 100.0 / n as f64, 50.0, 0.0))
            .collect();
        let d = power_diagram(&sites, &clip);
        d.sanity_check(&sites, &clip).expect("sane");
        for c in &d.cells {
            assert!((c.area - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn all_sites_equal() {
        let sites = vec![site(1.0, 3.0, 2.0); 5_000];
        let d = power_diagram(&sites, &square());
        d.sanity_check(&sites, &square()).expect("sane");
        assert!((d.cells[0].area - 16.0).abs() < 1e-12);
        assert!(d.cells[1..]
            .iter()
            .all(|c| c.polygon.is_none() && c.dominated_by == Some(0)));
    }

    #[test]
    fn sites_far_outside() {
        let sites = [
            site(-1e6, 2.0, 0.0),
            site(2.0, 1e7, 0.0),
            site(1e6, -1e6, 0.0),
            site(2.0, 2.0, -1e9),
        ];
        for d in both(&sites, &square()) {
            let total: f64 = d.cells.iter().map(|c| c.area).sum();
            assert!((total - 16.0).abs() < 1e-9);
        }
    }

    #[test]
    fn one_giant_weight_among_many() {
        // One site owns most of the clip: cells near it need the pyramid
        // search (the global maximum weight defeats the ring bound).
        let clip = ConvexPolygon::rectangle(0.0, 0.0, 100.0, 100.0).expect("clip");
        let mut next = rng(11);
        let mut sites: Vec<Site> = (0..3000)
            .map(|_| site(100.0 * next(), 100.0 * next(), next()))
            .collect();
        sites.push(site(50.0, 50.0, 1500.0));
        let d = power_diagram(&sites, &clip);
        d.sanity_check(&sites, &clip).expect("sane");
        let naive = power_diagram_naive(&sites, &clip);
        for (a, b) in d.cells.iter().zip(&naive.cells) {
            assert_eq!(a.dominated_by, b.dominated_by);
            assert!((a.area - b.area).abs() < 1e-9 * 1e4);
            let sa: Vec<usize> = a.neighbors.iter().map(|x| x.site).collect();
            let sb: Vec<usize> = b.neighbors.iter().map(|x| x.site).collect();
            assert_eq!(sa, sb);
        }
    }
}
