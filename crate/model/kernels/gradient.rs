//! The gradients of a convolution, for training (see `conv_op`; native only): the same patches
//! and products as the forward pass, transposed.
use super::feature_map::Activation;
use super::matmul::{matmul, workers, Product};
use super::patches::{convolve, gather_patches, tile_rows, Grid};
use super::plan::{Kernels, Pass};

/// Pixels per part of a weight gradient's sum (see [`Kernels::weight_gradients`]).
const PART_PIXELS: usize = 1024;

impl Kernels {
    /// Output channels.
    pub(crate) fn c_out(&self) -> usize {
        self.bias.len()
    }

    /// The gradient w.r.t. the `[K, H, W, C_in]` input from `grad`, the gradient w.r.t. the
    /// output before the activation (`[K, s·H, s·W, C_out]`, s = 2 when upsampled): a
    /// convolution of `grad` with the transposed kernels at the mirrored offsets.
    pub(crate) fn input_gradient(&self, grad: &[f32], grad_shape: [usize; 4]) -> Vec<f32> {
        let s = self.stride();
        let grid = Grid {
            size: [grad_shape[1] / s, grad_shape[2] / s],
            scale: s,
        };
        let pass = self.input_gradient_pass();
        let zeros = vec![0.0; self.c_in];
        convolve(
            grad,
            grad_shape,
            grid,
            &[pass],
            1,
            &zeros,
            Activation::Identity,
        )
    }

    /// Output pixel (s·i + phase) read input pixel (i + tap) through the block of (phase, tap),
    /// so input pixel (a, b) receives from output pixel (s·a + phase − s·tap) through its
    /// transpose: one pass of taps at those offsets (distinct: 9 plain, 16 upsampled), in
    /// row-major order so that neighbouring taps are copied together.
    fn input_gradient_pass(&self) -> Pass {
        let (s, c_in, c_out) = (self.stride() as isize, self.c_in, self.c_out());
        let mut blocks: Vec<((isize, isize), Vec<f32>)> = Vec::new();
        for pass in &self.passes {
            let phase = (pass.phase.0 as isize, pass.phase.1 as isize);
            for (t, &(dy, dx)) in pass.taps.iter().enumerate() {
                let mut block = vec![0.0; c_out * c_in];
                for i in 0..c_in {
                    let row = &pass.kernel[(t * c_in + i) * c_out..][..c_out];
                    for (o, &v) in row.iter().enumerate() {
                        block[o * c_in + i] = v;
                    }
                }
                blocks.push(((phase.0 - s * dy, phase.1 - s * dx), block));
            }
        }
        blocks.sort_by_key(|(offset, _)| *offset);
        Pass {
            taps: blocks.iter().map(|(offset, _)| *offset).collect(),
            kernel: blocks.into_iter().flat_map(|(_, block)| block).collect(),
            phase: (0, 0),
            cells: Vec::new(),
        }
    }

    /// The gradients w.r.t. the weights (`[C_out, C_in, 3, 3]`, flat) and the bias from the
    /// `[K, H, W, C_in]` input and `grad` (as for [`Kernels::input_gradient`]): per pass, its
    /// patches transposed times the gradient of the pixels it wrote, summed over the tiles of
    /// each worker, then over workers, then onto the kernel cells each tap summed.
    pub(crate) fn weight_gradients(
        &self,
        input: &[f32],
        shape: [usize; 4],
        grad: &[f32],
        grad_shape: [usize; 4],
    ) -> (Vec<f32>, Vec<f32>) {
        use rayon::prelude::*;
        let ([k, h, w, c_in], c_out, s) = (shape, self.c_out(), self.stride());
        let pixels = k * h * w;
        // Parts of a fixed size, summed in order: the gradients do not depend on the number of
        // threads or on how rayon splits the work (a resumed training repeats the same losses).
        // With fewer parts than workers, each product is split over the workers instead.
        let per_part = PART_PIXELS;
        let parallel = pixels.div_ceil(per_part) < workers();
        // Per part: per pass, patchesᵀ · gradient; and the gradient's sum over its pixels (each
        // pixel is written by one pass: the bias gradient).
        let parts: Vec<(Vec<Vec<f32>>, Vec<f32>)> = (0..pixels.div_ceil(per_part))
            .into_par_iter()
            .map(|part| {
                let (from, to) = (part * per_part, ((part + 1) * per_part).min(pixels));
                let (mut col, mut g) = (Vec::new(), Vec::new());
                let mut bias = vec![0.0; c_out];
                let grid = |scale| Grid {
                    size: [h, w],
                    scale,
                };
                let sums = self
                    .passes
                    .iter()
                    .map(|pass| {
                        let row_len = pass.taps.len() * c_in;
                        let tile = tile_rows(row_len);
                        col.resize(tile * row_len, 0.0);
                        g.resize(tile * c_out, 0.0);
                        let written = [(pass.phase.0 as isize, pass.phase.1 as isize)];
                        let mut sum = vec![0.0; row_len * c_out];
                        for start in (from..to).step_by(tile) {
                            let rows = tile.min(to - start);
                            let taps = &pass.taps;
                            gather_patches(&mut col, input, shape, grid(1), taps, start, rows);
                            gather_patches(
                                &mut g,
                                grad,
                                grad_shape,
                                grid(s),
                                &written,
                                start,
                                rows,
                            );
                            let size = [row_len, rows, c_out];
                            let how = Product {
                                lhs_transposed: true,
                                accumulate: true,
                                parallel,
                            };
                            matmul(&mut sum, &col, &g, size, how);
                            for px in g[..rows * c_out].chunks_exact(c_out) {
                                bias.iter_mut().zip(px).for_each(|(b, &v)| *b += v);
                            }
                        }
                        sum
                    })
                    .collect::<Vec<_>>();
                (sums, bias)
            })
            .collect();
        let mut parts = parts.into_iter();
        let (sums, bias) = parts
            .next()
            .map(|first| {
                parts.fold(first, |(mut sums, mut bias), (other, other_bias)| {
                    for (sum, other) in sums.iter_mut().zip(&other) {
                        sum.iter_mut().zip(other).for_each(|(a, &b)| *a += b);
                    }
                    bias.iter_mut().zip(&other_bias).for_each(|(a, &b)| *a += b);
                    (sums, bias)
                })
            })
            .unwrap_or_else(|| {
                // No pixels at all.
                let sums = self
                    .passes
                    .iter()
                    .map(|p| vec![0.0; p.taps.len() * c_in * c_out]);
                (sums.collect(), vec![0.0; c_out])
            });
        // Onto the kernel cells each tap summed, one output channel per task.
        let mut weight = vec![0.0; c_out * c_in * 9];
        weight
            .par_chunks_mut(c_in * 9)
            .enumerate()
            .for_each(|(o, weight)| {
                for (pass, sum) in self.passes.iter().zip(&sums) {
                    for (t, cells) in pass.cells.iter().enumerate() {
                        for i in 0..c_in {
                            let v = sum[(t * c_in + i) * c_out + o];
                            for &cell in cells {
                                weight[i * 9 + cell] += v;
                            }
                        }
                    }
                }
            });
        (weight, bias)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::init::conv3x3;
    use crate::model::kernels::feature_map::{values, FeatureMap};
    use burn::tensor::{Device, Distribution, Tensor};

    #[test]
    fn weight_gradients_do_not_depend_on_the_number_of_threads() {
        let device = Device::flex();
        device.seed(6);
        let conv = conv3x3([5, 7], &device);
        let x = Tensor::<4>::random([9, 5, 24, 24], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x);
        let grad = Tensor::<4>::random([9, 48, 48, 7], Distribution::Default, &device);
        let grad = values(grad);
        let kernels = Kernels::new(&[&conv], 5, true);
        let gradients = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let (w, b) = kernels.weight_gradients(&map.data, map.shape, &grad, [9, 48, 48, 7]);
                (w, b, kernels.input_gradient(&grad, [9, 48, 48, 7]))
            })
        };
        // Bit for bit: a resumed training must repeat the same losses.
        assert_eq!(gradients(1), gradients(3));
    }
}
