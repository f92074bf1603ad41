//! The portable dot-product kernel of the dense similarity rows: `R` rows against
//! one block of `L` transposed columns, every lane its own left-to-right sum from
//! zero with a multiply and an add (never a fused multiply-add). The exact f64
//! rows of `constraints` and the f32 filter of `filtered_rows` both use it where
//! their AVX kernels do not run; those keep the same order of operations.

use std::ops::{Add, Mul};

/// `R` rows' dot products with one block's `columns` (`d` chunks of `L`).
#[inline(always)]
pub(super) fn kernel<T, const R: usize, const L: usize>(
    rows: &[&[T]; R],
    columns: &[T],
) -> [[T; L]; R]
where
    T: Copy + Default + Add<Output = T> + Mul<Output = T>,
{
    let mut acc = [[T::default(); L]; R];
    let d = columns.len() / L;
    // Sliced to `d` up front so the loop below has no bounds checks to spill for.
    let rows: [&[T]; R] = rows.map(|row| &row[..d]);
    for (k, column) in columns.chunks_exact(L).enumerate() {
        let column: &[T; L] = column.try_into().expect("invariant: chunks of L");
        for r in 0..R {
            let x = rows[r][k];
            for lane in 0..L {
                acc[r][lane] = acc[r][lane] + x * column[lane];
            }
        }
    }
    acc
}
