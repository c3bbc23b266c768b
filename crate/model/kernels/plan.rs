//! How a convolution is prepared: its passes (one matrix product each) and their kernels, for
//! a map read directly or through its nearest 2× upsampling.
use burn::nn::conv::Conv2d;

use super::feature_map::{values, Activation, FeatureMap};
use super::matmul::for_each_chunk;
use super::patches::{convolve, Grid};

/// One matrix product of a convolution: the input offsets it reads and its kernel
/// (`[taps·C_in, C_out]`, rows ordered (tap, channel)), writing the output pixels
/// `(stride·i + phase.0, stride·j + phase.1)`.
#[derive(Debug)]
pub(super) struct Pass {
    pub(super) taps: Vec<(isize, isize)>,
    pub(super) kernel: Vec<f32>,
    pub(super) phase: (usize, usize),
    /// Per tap, the 3×3 kernel cells (ky·3 + kx) summed into it: how its gradient reaches the
    /// weights (training only: not read in wasm).
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    pub(super) cells: Vec<Vec<usize>>,
}

/// Convolutions prepared for [`FeatureMap::conv3x3`]: their passes and biases, with the
/// weights they were prepared from, so that a cache can tell whether they still hold.
#[derive(Debug)]
pub(crate) struct Kernels {
    pub(super) weights: Vec<Vec<f32>>,
    pub(super) bias: Vec<f32>,
    pub(super) c_in: usize,
    pub(super) upsampled: bool,
    pub(super) passes: Vec<Pass>,
}

impl Kernels {
    /// The weights and biases of `convs` over `c_in` input channels, each as flat values.
    pub(super) fn read(convs: &[&Conv2d], c_in: usize) -> (Vec<Vec<f32>>, Vec<f32>) {
        let mut weights = Vec::new();
        let mut bias = Vec::new();
        for conv in convs {
            let [c_out, c, kh, kw] = conv.weight.dims();
            assert_eq!(
                [c, kh, kw],
                [c_in, 3, 3],
                "a 3x3 kernel over {c_in} channels"
            );
            weights.push(values(conv.weight.val()));
            match &conv.bias {
                Some(b) => bias.extend(values(b.val())),
                None => bias.extend(std::iter::repeat_n(0.0, c_out)),
            }
        }
        (weights, bias)
    }

    /// Prepares `convs` (their outputs side by side) over `c_in` input channels (see
    /// [`Kernels::prepare`]).
    #[cfg(test)]
    pub(super) fn new(convs: &[&Conv2d], c_in: usize, upsampled: bool) -> Self {
        let (weights, bias) = Self::read(convs, c_in);
        Self::prepare(weights, bias, c_in, upsampled)
    }

    /// Prepares the flat `weights` (each `[C_out, C_in, 3, 3]`, their outputs side by side)
    /// and `bias` over `c_in` input channels, reading the input directly or, with
    /// `upsampled`, its nearest 2× upsampling.
    pub(crate) fn prepare(
        weights: Vec<Vec<f32>>,
        bias: Vec<f32>,
        c_in: usize,
        upsampled: bool,
    ) -> Self {
        let c_outs: Vec<usize> = weights.iter().map(|w| w.len() / (9 * c_in)).collect();
        let passes = passes(&weights, &c_outs, c_in, upsampled);
        Kernels {
            weights,
            bias,
            c_in,
            upsampled,
            passes,
        }
    }

    /// These convolutions (see [`FeatureMap::conv3x3`]) of the `[K, H, W, C]` map `input`.
    pub(crate) fn apply(
        &self,
        input: &[f32],
        shape: [usize; 4],
        activation: Activation,
    ) -> FeatureMap {
        debug_assert_eq!(shape[3], self.c_in);
        let [k, h, w, _] = shape;
        let grid = Grid {
            size: [h, w],
            scale: 1,
        };
        let stride = self.stride();
        let data = convolve(
            input,
            shape,
            grid,
            &self.passes,
            stride,
            &self.bias,
            activation,
        );
        FeatureMap {
            data,
            shape: [k, stride * h, stride * w, self.bias.len()],
        }
    }

    /// Output pixels per input pixel along each axis: 2 when the input is read upsampled.
    pub(super) fn stride(&self) -> usize {
        if self.upsampled {
            2
        } else {
            1
        }
    }
}

/// The rows of a 3×3 kernel that fall on each low-resolution row when the input was
/// upsampled by 2, for output phase 0 and 1: (row offset, kernel rows summed).
const UPSAMPLED_TAPS: [[(isize, &[usize]); 2]; 2] =
    [[(-1, &[0]), (0, &[1, 2])], [(0, &[0, 1]), (1, &[2])]];

/// A tap of a pass: the input offset and the kernel cells (ky·3 + kx) summed into it.
type Tap = ((isize, isize), Vec<usize>);

/// The passes of the convolutions `weights` (each `[C_out, C_in, 3, 3]`, C_out in `c_outs`; their
/// outputs side by side), reading the input directly or, with `upsampled`, its nearest 2×
/// upsampling.
#[inline(never)]
fn passes(weights: &[Vec<f32>], c_outs: &[usize], c_in: usize, upsampled: bool) -> Vec<Pass> {
    // Per pass: its phase and its taps.
    let layouts: Vec<((usize, usize), Vec<Tap>)> = if upsampled {
        let mut all = Vec::with_capacity(4);
        for (py, rows) in UPSAMPLED_TAPS.iter().enumerate() {
            for (px, cols) in UPSAMPLED_TAPS.iter().enumerate() {
                let mut taps = Vec::with_capacity(4);
                for &(dy, kys) in rows {
                    for &(dx, kxs) in cols {
                        let cells = kys
                            .iter()
                            .flat_map(|&ky| kxs.iter().map(move |&kx| ky * 3 + kx));
                        taps.push(((dy, dx), cells.collect()));
                    }
                }
                all.push(((py, px), taps));
            }
        }
        all
    } else {
        let taps = (0..9)
            .map(|cell| {
                (
                    ((cell / 3) as isize - 1, (cell % 3) as isize - 1),
                    vec![cell],
                )
            })
            .collect();
        vec![((0, 0), taps)]
    };
    let c_total: usize = c_outs.iter().sum();
    // Which weight (and its first column) each output column comes from.
    let mut columns = Vec::with_capacity(c_total);
    for (weight, &c_out) in weights.iter().zip(c_outs) {
        columns.extend((0..c_out).map(|o| (weight, o)));
    }
    // One kernel row (tap, input channel) per task: training prepares the kernels at every
    // step.
    let kernels: Vec<Vec<f32>> = layouts
        .iter()
        .map(|(_, taps)| {
            let mut kernel = vec![0.0; taps.len() * c_in * c_total];
            for_each_chunk(&mut kernel, c_total.max(1), |row, kernel_row| {
                let (cells, i) = (&taps[row / c_in].1, row % c_in);
                for (k, &(weight, o)) in kernel_row.iter_mut().zip(&columns) {
                    let w = &weight[(o * c_in + i) * 9..][..9];
                    *k = cells.iter().map(|&cell| w[cell]).sum();
                }
            });
            kernel
        })
        .collect();
    layouts
        .into_iter()
        .zip(kernels)
        .map(|((phase, taps), kernel)| {
            let (taps, cells) = taps.into_iter().unzip();
            Pass {
                taps,
                kernel,
                phase,
                cells,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::init::conv3x3;
    use crate::model::testing::max_abs_diff;
    use crate::model::upsample2;
    use burn::tensor::{Device, Distribution, Tensor};

    #[test]
    fn conv3x3_equals_burns_conv2d_plain_upsampled_and_stacked() {
        let device = Device::flex();
        device.seed(3);
        for (k, c_in, c_out, s) in [(3, 4, 8, 8), (2, 5, 3, 2), (9, 16, 4, 16)] {
            let a = conv3x3([c_in, c_out], &device);
            let b = conv3x3([c_in, 2], &device);
            let x = Tensor::<4>::random([k, c_in, s, s], Distribution::Default, &device);
            let map = FeatureMap::from_channels_first(x.clone());
            for upsampled in [false, true] {
                let input = if upsampled {
                    upsample2(x.clone())
                } else {
                    x.clone()
                };
                let kernels = Kernels::new(&[&a, &b], c_in, upsampled);
                let got = map
                    .conv3x3(&kernels, Activation::Relu)
                    .into_channels_first(&[c_out, 2], &device);
                let expected = [a.forward(input.clone()), b.forward(input)];
                for (g, e) in got.into_iter().zip(expected) {
                    let d = max_abs_diff(g, burn::tensor::activation::relu(e));
                    assert!(d < 1e-5, "{k} {c_in} {c_out} {s} {upsampled}: {d}");
                }
            }
        }
    }
}
