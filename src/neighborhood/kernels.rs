//! The dot-product kernels of the dense similarity rows, for the exact f64 rows
//! (`dense_rows`) and the f32 filter (`filtered_rows`) alike: `R` rows against
//! one block of `L` transposed columns, every lane its own left-to-right sum from
//! zero with a multiply and an add (never a fused multiply-add). One dispatch,
//! [`dot_tile`], runs the AVX version where the CPU has it; AVX's multiplies and
//! adds round exactly as the portable loop's, so the choice changes no bit.

use std::ops::{Add, Mul};

/// Rows one kernel call sums at once: 4 rows × 2 registers of lanes are 8 AVX
/// registers.
pub(super) const KERNEL_ROWS: usize = 4;

/// A float the kernels sum: f64 for the exact rows, f32 for the filter.
pub(super) trait Lane: Copy + Default + Add<Output = Self> + Mul<Output = Self> {
    /// [`kernel`] for [`KERNEL_ROWS`] rows in AVX intrinsics, `L` being two
    /// registers' worth of lanes (8 for f64, 16 for f32).
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    unsafe fn avx<const L: usize>(
        rows: &[&[Self]; KERNEL_ROWS],
        columns: &[Self],
    ) -> [[Self; L]; KERNEL_ROWS];
}

/// `R` rows' dot products with one block's `columns` (`d` chunks of `L`): the
/// portable kernel, which the compiler vectorises as it can.
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

/// [`kernel`] for [`KERNEL_ROWS`] rows, in AVX where the CPU has it (checked
/// per call by the standard library's cached detection), else portable. The
/// AVX version keeps the sums in registers (the compiler's own vectorisation
/// of [`kernel`] spilled them to the stack every step).
pub(super) fn dot_tile<T: Lane, const L: usize>(
    rows: &[&[T]; KERNEL_ROWS],
    columns: &[T],
) -> [[T; L]; KERNEL_ROWS] {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX, checked just above.
            return unsafe { T::avx::<L>(rows, columns) };
        }
    }
    kernel::<T, KERNEL_ROWS, L>(rows, columns)
}

/// The AVX kernel for one float type, written once: `$width` lanes per
/// register, two registers per row, the intrinsics of that type.
macro_rules! avx_kernel {
    ($t:ty, $name:ident, $width:expr, $load:ident, $store:ident, $add:ident, $mul:ident,
     $set1:ident, $zero:ident) => {
        /// [`kernel`] in AVX intrinsics for this type: multiplies and adds in
        /// the same order.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx")]
        unsafe fn $name<const L: usize>(
            rows: &[&[$t]; KERNEL_ROWS],
            columns: &[$t],
        ) -> [[$t; L]; KERNEL_ROWS] {
            use std::arch::x86_64::{$add, $load, $mul, $set1, $store, $zero};
            assert!(L == 2 * $width, "invariant: two registers of lanes");
            let d = columns.len() / L;
            let rows: [&[$t]; KERNEL_ROWS] = rows.map(|row| &row[..d]);
            let mut acc = [[$zero(); 2]; KERNEL_ROWS];
            for k in 0..d {
                let column = &columns[k * L..(k + 1) * L];
                // SAFETY: `column` holds L = 2 × width values, two loads.
                let (lo, hi) = unsafe {
                    (
                        $load(column.as_ptr()),
                        $load(column.as_ptr().add($width)),
                    )
                };
                for r in 0..KERNEL_ROWS {
                    let x = $set1(rows[r][k]);
                    acc[r][0] = $add(acc[r][0], $mul(x, lo));
                    acc[r][1] = $add(acc[r][1], $mul(x, hi));
                }
            }
            let mut out = [[<$t>::default(); L]; KERNEL_ROWS];
            for (o, a) in out.iter_mut().zip(&acc) {
                // SAFETY: `o` holds L = 2 × width values, two stores.
                unsafe {
                    $store(o.as_mut_ptr(), a[0]);
                    $store(o.as_mut_ptr().add($width), a[1]);
                }
            }
            out
        }
    };
}

avx_kernel!(
    f64,
    avx_f64,
    4,
    _mm256_loadu_pd,
    _mm256_storeu_pd,
    _mm256_add_pd,
    _mm256_mul_pd,
    _mm256_set1_pd,
    _mm256_setzero_pd
);
avx_kernel!(
    f32,
    avx_f32,
    8,
    _mm256_loadu_ps,
    _mm256_storeu_ps,
    _mm256_add_ps,
    _mm256_mul_ps,
    _mm256_set1_ps,
    _mm256_setzero_ps
);

impl Lane for f64 {
    #[cfg(target_arch = "x86_64")]
    unsafe fn avx<const L: usize>(
        rows: &[&[f64]; KERNEL_ROWS],
        columns: &[f64],
    ) -> [[f64; L]; KERNEL_ROWS] {
        // SAFETY: the caller checked AVX.
        unsafe { avx_f64::<L>(rows, columns) }
    }
}

impl Lane for f32 {
    #[cfg(target_arch = "x86_64")]
    unsafe fn avx<const L: usize>(
        rows: &[&[f32]; KERNEL_ROWS],
        columns: &[f32],
    ) -> [[f32; L]; KERNEL_ROWS] {
        // SAFETY: the caller checked AVX.
        unsafe { avx_f32::<L>(rows, columns) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dispatched kernel equals the portable one bit for bit, f64 and f32.
    #[test]
    fn dispatch_matches_the_portable_kernel() {
        let d = 7;
        let v = |i: usize| ((i * 7919) % 1000) as f64 / 37.0 - 13.0;
        let rows64: Vec<Vec<f64>> = (0..KERNEL_ROWS)
            .map(|r| (0..d).map(|k| v(r * 31 + k)).collect())
            .collect();
        let cols64: Vec<f64> = (0..d * 8).map(|i| v(i + 500)).collect();
        let r64: [&[f64]; KERNEL_ROWS] = std::array::from_fn(|r| rows64[r].as_slice());
        assert_eq!(
            dot_tile::<f64, 8>(&r64, &cols64),
            kernel::<f64, KERNEL_ROWS, 8>(&r64, &cols64)
        );
        let rows32: Vec<Vec<f32>> = rows64
            .iter()
            .map(|r| r.iter().map(|x| *x as f32).collect())
            .collect();
        let cols32: Vec<f32> = (0..d * 16).map(|i| v(i + 900) as f32).collect();
        let r32: [&[f32]; KERNEL_ROWS] = std::array::from_fn(|r| rows32[r].as_slice());
        assert_eq!(
            dot_tile::<f32, 16>(&r32, &cols32),
            kernel::<f32, KERNEL_ROWS, 16>(&r32, &cols32)
        );
    }
}
