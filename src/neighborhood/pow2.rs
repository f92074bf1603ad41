//! Exact rescaling by a power of two: what the projections and the matching
//! divide their inputs by, so that sums of squares and potentials cannot
//! overflow while every ratio and tie stays exactly as it was.

/// The largest power of two not above `x` (finite, > 0); dividing by it is exact.
pub(crate) fn pow2_floor(x: f64) -> f64 {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    if x >= f64::MIN_POSITIVE {
        f64::from_bits(x.to_bits() & EXPONENT)
    } else {
        // Subnormal: lift into the normal range first.
        f64::from_bits((x * TWO_52).to_bits() & EXPONENT) / TWO_52
    }
}
