//! 2×2 max pooling of channels-last maps, and its gradient for training.
use super::feature_map::FeatureMap;

/// 2×2 max pooling with stride 2 of the `[K, H, W, C]` map `input`, and for each output value
/// which of its four inputs (row-major, the first of equals) it came from: where its gradient
/// goes.
pub(crate) fn max_pool2_indexed(input: &[f32], [k, h, w, c]: [usize; 4]) -> (FeatureMap, Vec<u8>) {
    let (oh, ow) = (h / 2, w / 2);
    let mut out = vec![0.0; k * oh * ow * c];
    let mut from = vec![0u8; out.len()];
    // One output row per task.
    let pool_row = |row: usize, (out, from): (&mut [f32], &mut [u8])| {
        let (f, i) = (row / oh, row % oh);
        for (j, (dst, idx)) in out
            .chunks_exact_mut(c)
            .zip(from.chunks_exact_mut(c))
            .enumerate()
        {
            let at = |y: usize, x: usize| &input[((f * h + y) * w + x) * c..][..c];
            let quad = [
                at(2 * i, 2 * j),
                at(2 * i, 2 * j + 1),
                at(2 * i + 1, 2 * j),
                at(2 * i + 1, 2 * j + 1),
            ];
            for ch in 0..c {
                let (mut best, mut which) = (quad[0][ch], 0);
                for (q, v) in quad.iter().enumerate().skip(1) {
                    if v[ch] > best {
                        (best, which) = (v[ch], q as u8);
                    }
                }
                dst[ch] = best;
                idx[ch] = which;
            }
        }
    };
    let row = (ow * c).max(1);
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        let rows = out.par_chunks_mut(row).zip(from.par_chunks_mut(row));
        rows.enumerate().for_each(|(r, chunks)| pool_row(r, chunks));
    }
    #[cfg(target_arch = "wasm32")]
    {
        let rows = out.chunks_mut(row).zip(from.chunks_mut(row));
        rows.enumerate().for_each(|(r, chunks)| pool_row(r, chunks));
    }
    let map = FeatureMap {
        data: out,
        shape: [k, oh, ow, c],
    };
    (map, from)
}

/// The gradient w.r.t. the `[K, H, W, C]` input of [`max_pool2_indexed`] from the
/// gradient `grad` w.r.t. its output and the `from` indices it returned.
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn max_pool2_gradient(grad: &[f32], from: &[u8], [k, h, w, c]: [usize; 4]) -> Vec<f32> {
    use rayon::prelude::*;
    let ow = w / 2;
    let mut input = vec![0.0; k * h * w * c];
    // Each output row spreads onto two input rows: one pair per task.
    input
        .par_chunks_mut((2 * w * c).max(1))
        .enumerate()
        .for_each(|(row, input)| {
            let at = row * ow * c;
            let (grad, from) = (&grad[at..at + ow * c], &from[at..at + ow * c]);
            for (j, (g, idx)) in grad.chunks_exact(c).zip(from.chunks_exact(c)).enumerate() {
                for ch in 0..c {
                    let q = idx[ch] as usize;
                    input[((q / 2) * w + 2 * j + q % 2) * c + ch] = g[ch];
                }
            }
        });
    input
}
