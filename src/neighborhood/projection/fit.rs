//! The per-axis min–max rescale of projected points into a box
//! (method-reference §4.1 step 3).

use crate::geom::Point;

/// Rescales points per axis (min–max) into the box with corners `lo` and `hi`
/// (method-reference §4.1 step 3, without the prototype's halving of the y range).
///
/// On each axis the smallest coordinate maps to `lo` and the largest to `hi` (if
/// `lo > hi` the axis is mirrored). A single point, or a zero range on an axis, maps to the
/// box's midpoint on that axis. Non-finite coordinates are left out of the range and map to
/// the midpoint; non-finite box corners count as 0. The output is finite.
pub fn fit_into(points: &[Point], lo: Point, hi: Point) -> Vec<Point> {
    let xs = rescale_axis(
        points.iter().map(|p| p.x),
        finite_or_zero(lo.x),
        finite_or_zero(hi.x),
    );
    let ys = rescale_axis(
        points.iter().map(|p| p.y),
        finite_or_zero(lo.y),
        finite_or_zero(hi.y),
    );
    xs.into_iter()
        .zip(ys)
        .map(|(x, y)| Point::new(x, y))
        .collect()
}

/// One axis of [`fit_into`].
fn rescale_axis(values: impl Iterator<Item = f64> + Clone, lo: f64, hi: f64) -> Vec<f64> {
    let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.clone().filter(|v| v.is_finite()) {
        min = min.min(v);
        max = max.max(v);
    }
    // lo·(1−t) + hi·t is exact at both ends and cannot overflow for finite corners.
    let lerp = |t: f64| lo * (1.0 - t) + hi * t;
    let mid = lerp(0.5);
    // Halving before subtracting keeps the range finite even for ±f64::MAX.
    let half_range = 0.5 * max - 0.5 * min;
    values
        .map(|v| {
            if !v.is_finite() || half_range.is_nan() || half_range <= 0.0 {
                mid
            } else {
                lerp(((0.5 * v - 0.5 * min) / half_range).clamp(0.0, 1.0))
            }
        })
        .collect()
}

fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_into_rescales_each_axis_independently() {
        let pts = [
            Point::new(-1.0, 10.0),
            Point::new(3.0, 20.0),
            Point::new(1.0, 15.0),
        ];
        let out = fit_into(&pts, Point::new(0.0, 0.0), Point::new(100.0, 50.0));
        assert_eq!(
            out,
            vec![
                Point::new(0.0, 0.0),
                Point::new(100.0, 50.0),
                Point::new(50.0, 25.0)
            ]
        );
    }

    #[test]
    fn fit_into_degenerate_axes_go_to_the_midpoint() {
        let lo = Point::new(10.0, 20.0);
        let hi = Point::new(30.0, 60.0);
        assert_eq!(
            fit_into(&[Point::new(5.0, 5.0)], lo, hi),
            vec![Point::new(20.0, 40.0)]
        );
        let out = fit_into(&[Point::new(1.0, 7.0), Point::new(2.0, 7.0)], lo, hi);
        assert_eq!(out, vec![Point::new(10.0, 40.0), Point::new(30.0, 40.0)]);
        let out = fit_into(
            &[
                Point::new(f64::NAN, 0.0),
                Point::new(-f64::MAX, f64::INFINITY),
                Point::new(f64::MAX, 1.0),
            ],
            lo,
            hi,
        );
        assert_eq!(
            out,
            vec![
                Point::new(20.0, 20.0),
                Point::new(10.0, 40.0),
                Point::new(30.0, 60.0)
            ]
        );
        assert!(fit_into(&[], lo, hi).is_empty());
        let out = fit_into(
            &[Point::new(1.0, 2.0)],
            Point::new(f64::NAN, 0.0),
            Point::new(4.0, 4.0),
        );
        assert_eq!(out, vec![Point::new(2.0, 2.0)]);
    }
}
