//! The kernels' matrix product (`gemm`) and their split over rayon's workers (natively; wasm
//! has no threads).

/// How [`matmul`] reads and writes.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Product {
    /// `lhs` is stored transposed, as `[k, m]`.
    pub(super) lhs_transposed: bool,
    /// `out += lhs · rhs` instead of `out = lhs · rhs`.
    pub(super) accumulate: bool,
    /// The product is split over the workers (natively: not read in wasm).
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    pub(super) parallel: bool,
}

/// `out = lhs · rhs` for row-major `rhs` `[k, n]`, `out` `[m, n]` and `lhs` `[m, k]`, read and
/// written as `how` says.
pub(super) fn matmul(
    out: &mut [f32],
    lhs: &[f32],
    rhs: &[f32],
    [m, k, n]: [usize; 3],
    how: Product,
) {
    #[cfg(not(target_arch = "wasm32"))]
    let parallelism = if how.parallel {
        gemm::Parallelism::Rayon(workers())
    } else {
        gemm::Parallelism::None
    };
    #[cfg(target_arch = "wasm32")]
    let parallelism = gemm::Parallelism::None;
    assert!(out.len() >= m * n && lhs.len() >= m * k && rhs.len() >= k * n);
    let (lhs_cs, lhs_rs) = if how.lhs_transposed {
        (m as isize, 1)
    } else {
        (1, k as isize)
    };
    // SAFETY: the bounds above cover every element gemm reads or writes with these strides.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            out.as_mut_ptr(),
            1,
            n as isize,
            how.accumulate,
            lhs.as_ptr(),
            lhs_cs,
            lhs_rs,
            rhs.as_ptr(),
            1,
            n as isize,
            if how.accumulate { 1.0 } else { 0.0 },
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

/// Runs `f(index, chunk)` over `chunk`-sized pieces of `out`, in parallel natively (wasm has
/// no threads).
pub(super) fn for_each_chunk<T: Send>(
    out: &mut [T],
    chunk: usize,
    f: impl Fn(usize, &mut [T]) + Send + Sync,
) {
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        out.par_chunks_mut(chunk)
            .enumerate()
            .for_each(|(i, c)| f(i, c));
    }
    #[cfg(target_arch = "wasm32")]
    out.chunks_mut(chunk).enumerate().for_each(|(i, c)| f(i, c));
}

/// A `len`-long vector filled by `f(index, chunk)` over `chunk`-sized pieces (as
/// [`for_each_chunk`]), each piece zeroed first by the worker that fills it, not all of it
/// up front on one thread.
pub(super) fn zeroed_chunks(
    len: usize,
    chunk: usize,
    f: impl Fn(usize, &mut [f32]) + Send + Sync,
) -> Vec<f32> {
    let mut out: Vec<f32> = Vec::with_capacity(len);
    for_each_chunk(
        &mut out.spare_capacity_mut()[..len],
        chunk.max(1),
        |i, piece| {
            piece.iter_mut().for_each(|x| {
                x.write(0.0);
            });
            // SAFETY: every element of the piece was just initialised, and MaybeUninit<f32> has
            // the layout of f32.
            let piece = unsafe {
                std::slice::from_raw_parts_mut(piece.as_mut_ptr().cast::<f32>(), piece.len())
            };
            f(i, piece)
        },
    );
    // SAFETY: the pieces cover the first `len` elements, each initialised above.
    unsafe { out.set_len(len) };
    out
}

/// The threads the kernels split their work over: rayon's, or 1 in wasm.
pub(super) fn workers() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    return rayon::current_num_threads();
    #[cfg(target_arch = "wasm32")]
    1
}
