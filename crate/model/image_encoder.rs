use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::Conv2d;
use burn::nn::Linear;
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

use super::init::conv3x3;
use super::kernels::{Activation, KernelCache};
use super::maps::Maps;

/// Configuration of an [`ImageEncoder`].
#[derive(Config, Debug)]
pub struct ImageEncoderConfig {
    /// Input channels: 4 for DMBN (a plane holding t, then RGB), 3 for DMBN-PTE (RGB).
    pub channels: usize,
    /// Filters of the conv blocks; each block halves the frame, which must end at 2x2.
    pub filters: Vec<usize>,
    /// Size of the encoding (H).
    #[config(default = 128)]
    pub hidden: usize,
}

/// The per-context image encoder e_image: blocks of Conv 3x3 'same' + ReLU + MaxPool 2x2
/// down to 2x2, flatten, Dense H + ReLU.
#[derive(Module, Debug)]
pub struct ImageEncoder {
    /// One 3x3 convolution per block.
    pub convs: Vec<Conv2d>,
    /// Flattened 2x2 feature map to the encoding.
    pub dense: Linear,
    /// The inference kernels prepared from the convolutions above.
    #[module(skip)]
    pub(crate) kernels: KernelCache,
}

impl ImageEncoderConfig {
    /// Builds the encoder.
    pub fn init(&self, device: &Device) -> ImageEncoder {
        let mut channels = self.channels;
        let convs = self
            .filters
            .iter()
            .map(|&filters| {
                let conv = conv3x3([channels, filters], device);
                channels = filters;
                conv
            })
            .collect();
        ImageEncoder {
            convs,
            dense: super::init::dense(channels * 4, self.hidden, device),
            kernels: KernelCache::default(),
        }
    }
}

impl ImageEncoder {
    /// `[K, C, S, S]` frames (S = 2^(blocks + 1)) to `[K, H]` encodings. Training runs the
    /// layers as differentiable operations (on flex those of `conv_op`, elsewhere burn's own
    /// layers), inference on the kernels; `Maps` picks the path.
    pub fn forward(&self, images: Tensor<4>) -> Tensor<2> {
        let mut maps = Maps::new(images, self.convs.first());
        for (i, conv) in self.convs.iter().enumerate() {
            maps = maps
                .conv3x3(i, &[conv], false, Activation::Relu, &self.kernels)
                .max_pool2();
        }
        let channels = maps.channels();
        self.encode(maps.into_channels_first(&[channels]).remove(0))
    }

    /// The last feature maps `[K, C, 2, 2]` to the encodings.
    fn encode(&self, x: Tensor<4>) -> Tensor<2> {
        let [k, c, h, w] = x.dims();
        relu(self.dense.forward(x.reshape([k, c * h * w])))
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::model::testing::{assert_gradient_close, max_abs, max_abs_diff};
    use burn::tensor::Distribution;

    /// The conv blocks through burn's own layers: what the other paths must equal.
    fn convs_burn(encoder: &ImageEncoder, images: Tensor<4>) -> Tensor<4> {
        let pool = burn::nn::pool::MaxPool2dConfig::new([2, 2]).init();
        encoder
            .convs
            .iter()
            .fold(images, |x, conv| pool.forward(relu(conv.forward(x))))
    }

    #[test]
    fn inference_and_training_equal_burns_layers_in_values_and_gradients() {
        // One encoder for all paths: two seeded inits can differ when tests run in parallel
        // (the generator is shared).
        let ad = Device::flex().autodiff();
        let encoder = ImageEncoderConfig::new(4, vec![8, 16, 16]).init(&ad);
        let device = Device::flex();
        let frames = Tensor::<4>::random([3, 4, 16, 16], Distribution::Default, &device);
        let fast = encoder.valid().forward(frames.clone());
        let frames = Tensor::<4>::from_data(frames.into_data(), &ad);
        let tracked = encoder.forward(frames.clone());
        let expected = encoder.encode(convs_burn(&encoder, frames));
        assert!(max_abs_diff(tracked.clone().inner(), fast) < 1e-5);
        assert!(max_abs_diff(tracked.clone().inner(), expected.clone().inner()) < 1e-5);
        // A weighted sum, so that every gradient differs from pixel to pixel.
        let weights = Tensor::<2>::random(tracked.dims(), Distribution::Default, &ad);
        let grads = (tracked * weights.clone()).sum().backward();
        let expected = (expected * weights).sum().backward();
        for conv in &encoder.convs {
            let got = conv.weight.grad(&grads);
            let want = conv.weight.grad(&expected).expect("burn's gradient");
            // The bias is held to the weight's scale.
            let scale = max_abs(want.clone());
            assert_gradient_close(got.expect("a gradient for every convolution"), want, scale);
            let bias = conv.bias.as_ref().unwrap();
            let got = bias.grad(&grads).expect("bias gradient");
            assert_gradient_close(got, bias.grad(&expected).unwrap(), scale);
        }
    }

    #[test]
    fn other_autodiff_backends_train_through_burns_layers() {
        // Gradient checkpointing is another autodiff backend than the one conv_op runs on.
        let device = Device::flex().autodiff().gradient_checkpointing();
        let encoder = ImageEncoderConfig::new(4, vec![8, 16]).init(&device);
        let frames = Tensor::<4>::random([2, 4, 8, 8], Distribution::Default, &device);
        let got = encoder.forward(frames.clone());
        let want = encoder.encode(convs_burn(&encoder, frames));
        assert_eq!(max_abs_diff(got.clone().inner(), want.inner()), 0.0);
        let grads = got.sum().backward();
        for conv in &encoder.convs {
            assert!(conv.weight.grad(&grads).is_some());
        }
    }
}
