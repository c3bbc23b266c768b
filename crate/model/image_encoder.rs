use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::Conv2d;
use burn::nn::pool::MaxPool2dConfig;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

use super::feature_map::{is_tracked, new_conv3x3, Activation, FeatureMap, KernelCache};

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
    pub kernels: KernelCache,
}

impl ImageEncoderConfig {
    /// Builds the encoder.
    pub fn init(&self, device: &Device) -> ImageEncoder {
        let mut channels = self.channels;
        let convs = self
            .filters
            .iter()
            .map(|&filters| {
                let conv = new_conv3x3([channels, filters], device);
                channels = filters;
                conv
            })
            .collect();
        ImageEncoder {
            convs,
            dense: LinearConfig::new(channels * 4, self.hidden).init(device),
            kernels: KernelCache::default(),
        }
    }
}

impl ImageEncoder {
    /// `[K, C, S, S]` frames (S = 2^(blocks + 1)) to `[K, H]` encodings: through burn's
    /// differentiable layers when training (see [`is_tracked`]), else through the inference kernels
    /// ([`FeatureMap`]).
    pub fn forward(&self, images: Tensor<4>) -> Tensor<2> {
        let tracked = self.convs.first().map(|c| is_tracked(&c.weight.val()));
        let x = if is_tracked(&images) || tracked.unwrap_or(false) {
            let pool = MaxPool2dConfig::new([2, 2]).init();
            self.convs
                .iter()
                .fold(images, |x, conv| pool.forward(relu(conv.forward(x))))
        } else {
            let device = images.device();
            let mut map = FeatureMap::from_channels_first(images);
            for (i, conv) in self.convs.iter().enumerate() {
                let kernels = self.kernels.get(i, &[conv], map.shape[3], false);
                map = map.conv3x3(&kernels, Activation::Relu).max_pool2();
            }
            let c = map.shape[3];
            map.into_channels_first(&[c], &device).remove(0)
        };
        let [k, c, h, w] = x.dims();
        relu(self.dense.forward(x.reshape([k, c * h * w])))
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use burn::tensor::Distribution;

    #[test]
    fn inference_kernels_equal_the_differentiable_layers_and_training_reaches_the_convs() {
        // One encoder for both paths: two seeded inits can differ when tests run in parallel
        // (the generator is shared).
        let ad = Device::flex().autodiff();
        let encoder = ImageEncoderConfig::new(4, vec![8, 16, 16]).init(&ad);
        let device = Device::flex();
        let frames = Tensor::<4>::random([3, 4, 16, 16], Distribution::Default, &device);
        let fast = encoder.valid().forward(frames.clone());
        let tracked = encoder.forward(Tensor::from_data(frames.into_data(), &ad));
        let diff: f32 = (tracked.clone().inner() - fast).abs().max().into_scalar();
        assert!(diff < 1e-5, "{diff}");
        let grads = tracked.sum().backward();
        for conv in &encoder.convs {
            assert!(conv.weight.grad(&grads).is_some());
        }
    }
}
