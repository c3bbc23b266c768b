//! The maps the kernels read and write, and the layout changes at a network's two ends.
use burn::tensor::{Device, Tensor, TensorData};

use super::plan::Kernels;
use super::pool::max_pool2_indexed;

/// A stack of K feature maps, `[K, H, W, C]` in row-major order (channels last).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FeatureMap {
    /// The values, `K·H·W·C` of them.
    pub(crate) data: Vec<f32>,
    /// `[K, H, W, C]`.
    pub(crate) shape: [usize; 4],
}

/// What follows a convolution, applied as its result is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Activation {
    /// Nothing.
    Identity,
    /// max(0, x).
    Relu,
}

pub(super) use crate::model::values;

impl FeatureMap {
    /// From a channels-first `[K, C, H, W]` tensor.
    pub(crate) fn from_channels_first(x: Tensor<4>) -> Self {
        let [k, c, h, w] = x.dims();
        let src = values(x);
        let mut data = vec![0.0; src.len()];
        for f in 0..k {
            for ch in 0..c {
                let plane = &src[(f * c + ch) * h * w..][..h * w];
                for (p, &v) in plane.iter().enumerate() {
                    data[(f * h * w + p) * c + ch] = v;
                }
            }
        }
        FeatureMap {
            data,
            shape: [k, h, w, c],
        }
    }

    /// Channels-first tensors on `device` of consecutive channel groups of `sizes` channels,
    /// each `[K, size, H, W]`.
    pub(crate) fn into_channels_first(self, sizes: &[usize], device: &Device) -> Vec<Tensor<4>> {
        let [k, h, w, c] = self.shape;
        debug_assert_eq!(sizes.iter().sum::<usize>(), c);
        let mut first = 0;
        sizes
            .iter()
            .map(|&size| {
                let mut out = vec![0.0; k * size * h * w];
                for f in 0..k {
                    for p in 0..h * w {
                        let src = &self.data[(f * h * w + p) * c + first..][..size];
                        for (ch, &v) in src.iter().enumerate() {
                            out[(f * size + ch) * h * w + p] = v;
                        }
                    }
                }
                first += size;
                Tensor::from_data(TensorData::new(out, [k, size, h, w]), device)
            })
            .collect()
    }

    /// The prepared 3×3 'same' convolutions `kernels` (their outputs side by side as channels)
    /// of this map or, if they were prepared so, of its nearest 2× upsampling, followed by
    /// `activation`.
    pub(crate) fn conv3x3(&self, kernels: &Kernels, activation: Activation) -> Self {
        kernels.apply(&self.data, self.shape, activation)
    }

    /// 2×2 max pooling with stride 2.
    pub(crate) fn max_pool2(&self) -> Self {
        max_pool2_indexed(&self.data, self.shape).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::testing::max_abs_diff;
    use burn::nn::pool::MaxPool2dConfig;
    use burn::tensor::Distribution;

    #[test]
    fn max_pool2_and_layout_round_trip() {
        let device = Device::flex();
        device.seed(4);
        let x = Tensor::<4>::random([2, 3, 4, 6], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x.clone());
        let back = map.clone().into_channels_first(&[3], &device).remove(0);
        assert_eq!(max_abs_diff(back, x.clone()), 0.0);
        let pooled = map.max_pool2().into_channels_first(&[3], &device).remove(0);
        let expected = MaxPool2dConfig::new([2, 2]).init().forward(x);
        assert_eq!(max_abs_diff(pooled, expected), 0.0);
    }
}
