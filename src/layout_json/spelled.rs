//! One cell as the layout-JSON writer spells it: its polygon and site with
//! the numbers rounded to a number of decimals (or in full precision), the
//! unit that `precision` chooses the grid of and checks, `checks` keeps from
//! one document to the next, and `write` prints.

use crate::geom::{ConvexPolygon, Point};
use crate::layout::Layout;

/// One cell as the writer spells it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Spelled {
    /// Decimals of its numbers; `None` for full precision.
    pub(super) places: Option<i32>,
    /// Its polygon's vertices, rounded (repeated vertices dropped).
    pub(super) polygon: Vec<Point>,
    /// Its site, rounded.
    pub(super) site: Point,
}

/// `v` rounded to `places` decimals (`None`: as is), never `-0.0`.
///
/// Dividing the rounded integer by the power of ten gives the double nearest
/// to the decimal, so a shortest round-trip printer writes exactly that
/// decimal (no `0.30000000000000004` tails).
pub(super) fn round(v: f64, places: Option<i32>) -> f64 {
    let Some(places) = places else {
        return v + 0.0;
    };
    let scale = 10f64.powi(places);
    let r = (v * scale).round() / scale;
    // `+ 0.0` turns -0.0 into 0.0 (IEEE: -0 + +0 = +0).
    if r.is_finite() {
        r + 0.0
    } else {
        v + 0.0
    }
}

/// Every cell of `layout` spelled in full precision (the stored state).
pub(super) fn exact(layout: &Layout) -> Vec<Spelled> {
    layout
        .cells
        .iter()
        .map(|c| spell(&c.polygon, c.site, None))
        .collect()
}

pub(super) fn spell(polygon: &ConvexPolygon, site: Point, places: Option<i32>) -> Spelled {
    let r = |p: Point| Point::new(round(p.x, places), round(p.y, places));
    let mut points: Vec<Point> = Vec::with_capacity(polygon.len());
    for p in polygon.points() {
        let q = r(*p);
        if points.last() != Some(&q) {
            points.push(q);
        }
    }
    while points.len() > 1 && points.first() == points.last() {
        points.pop();
    }
    Spelled {
        places,
        polygon: points,
        site: r(site),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_is_to_decimals_and_never_negative_zero() {
        assert_eq!(round(1.0 / 3.0, Some(4)), 0.3333);
        assert_eq!(round(-1e-9, Some(4)).to_string(), "0");
        assert_eq!(round(-0.0, None).to_string(), "0");
        assert_eq!(round(0.1 + 0.2, Some(4)), 0.3);
        assert_eq!(round(1.0 / 3.0, None), 1.0 / 3.0);
    }
}
