use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::Conv2d;
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Tensor};

use super::feature_map::{is_tracked, new_conv3x3, Activation, FeatureMap, KernelCache};
use super::gaussian::bounded_sigma;

/// Filters of the two convolutions between the last upsampling block and the heads.
pub const IMAGE_DECODER_TAIL: [usize; 2] = [16, 8];

/// Configuration of an [`ImageDecoder`].
#[derive(Config, Debug)]
pub struct ImageDecoderConfig {
    /// Width of the shared decoder layer it reads, reshaped to `[input / 4, 2, 2]`.
    #[config(default = 1024)]
    pub input: usize,
    /// Filters of the upsampling blocks; each doubles the frame, starting from 2x2.
    pub filters: Vec<usize>,
    /// Lower bound of the predicted σ.
    #[config(default = 0.01)]
    pub sigma_floor: f64,
}

/// The image decoder: reshape to 2x2, blocks of Conv 3x3 + ReLU + nearest UpSampling x2,
/// Conv 16 + ReLU, Conv 8 + ReLU, then two 3-channel 3x3 heads: the mean (through a sigmoid,
/// since pixels lie in [0, 1]) and σ (see [`bounded_sigma`]).
#[derive(Module, Debug)]
pub struct ImageDecoder {
    /// One 3x3 convolution per upsampling block.
    pub blocks: Vec<Conv2d>,
    /// Conv 16 and Conv 8 at full resolution.
    pub tail: Vec<Conv2d>,
    /// 3-channel mean head.
    pub mean: Conv2d,
    /// 3-channel σ head.
    pub sigma: Conv2d,
    /// Lower bound of σ.
    pub sigma_floor: f64,
    /// The inference kernels prepared from the convolutions above.
    #[module(skip)]
    pub kernels: KernelCache,
}

impl ImageDecoderConfig {
    /// Builds the decoder.
    pub fn init(&self, device: &Device) -> ImageDecoder {
        let mut channels = self.input / 4;
        let mut layers = |filters: &[usize]| -> Vec<Conv2d> {
            filters
                .iter()
                .map(|&f| {
                    let conv = new_conv3x3([channels, f], device);
                    channels = f;
                    conv
                })
                .collect()
        };
        let blocks = layers(&self.filters);
        let tail = layers(&IMAGE_DECODER_TAIL);
        ImageDecoder {
            blocks,
            tail,
            mean: new_conv3x3([channels, 3], device),
            sigma: new_conv3x3([channels, 3], device),
            sigma_floor: self.sigma_floor,
            kernels: KernelCache::default(),
        }
    }
}

impl ImageDecoder {
    /// `[K, input]` to the mean and σ frames, each `[K, 3, S, S]` with S = 2^(blocks + 1):
    /// through burn's differentiable layers when training (see [`is_tracked`]), else through the
    /// faster inference kernels ([`FeatureMap`]); the two agree to float rounding.
    pub fn forward(&self, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
        if is_tracked(&x) || is_tracked(&self.mean.weight.val()) {
            self.forward_differentiable(x)
        } else {
            self.forward_inference(x)
        }
    }

    /// [`ImageDecoder::forward`] through burn's layers (autodiff-capable).
    pub fn forward_differentiable(&self, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
        let [k, width] = x.dims();
        let mut x = x.reshape([k, width / 4, 2, 2]);
        for conv in &self.blocks {
            x = upsample2(relu(conv.forward(x)));
        }
        for conv in &self.tail {
            x = relu(conv.forward(x));
        }
        let mean = sigmoid(self.mean.forward(x.clone()));
        let sigma = bounded_sigma(self.sigma.forward(x), self.sigma_floor);
        (mean, sigma)
    }

    /// [`ImageDecoder::forward`] through the inference kernels: each upsampling is folded into
    /// the convolution that reads it, and both heads share one product.
    pub fn forward_inference(&self, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
        let [k, width] = x.dims();
        let device = x.device();
        let mut map = FeatureMap::from_channels_first(x.reshape([k, width / 4, 2, 2]));
        let layers = self.blocks.len() + self.tail.len();
        for (i, conv) in self.blocks.iter().chain(&self.tail).enumerate() {
            // Every block's output is upsampled, so the convolution after one reads it so.
            let upsampled = i > 0 && i <= self.blocks.len();
            let kernels = self.kernels.get(i, &[conv], map.shape[3], upsampled);
            map = map.conv3x3(&kernels, Activation::Relu);
        }
        let heads = [&self.mean, &self.sigma];
        let kernels = self.kernels.get(layers, &heads, map.shape[3], false);
        let mut heads = map
            .conv3x3(&kernels, Activation::Identity)
            .into_channels_first(&[3, 3], &device)
            .into_iter();
        let (mean, sigma) = (heads.next().expect("mean"), heads.next().expect("σ"));
        (sigmoid(mean), bounded_sigma(sigma, self.sigma_floor))
    }
}

/// Nearest-neighbour upsampling by 2: `[K, C, H, W]` to `[K, C, 2H, 2W]`.
pub fn upsample2(x: Tensor<4>) -> Tensor<4> {
    let [k, c, h, w] = x.dims();
    x.reshape([k, c, h, 1, w, 1])
        .expand([k, c, h, 2, w, 2])
        .reshape([k, c, 2 * h, 2 * w])
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use burn::tensor::Distribution;

    fn decoder(device: &Device) -> ImageDecoder {
        device.seed(5);
        ImageDecoderConfig::new(vec![16, 8, 8])
            .with_input(64)
            .init(device)
    }

    #[test]
    fn upsample2_repeats_each_pixel() {
        let device = Device::flex();
        let x = Tensor::<4>::from_floats([[[[1.0, 2.0], [3.0, 4.0]]]], &device);
        let y: Vec<f32> = upsample2(x).into_data().try_to_vec().unwrap();
        #[rustfmt::skip]
        let expected = [
            1.0, 1.0, 2.0, 2.0,
            1.0, 1.0, 2.0, 2.0,
            3.0, 3.0, 4.0, 4.0,
            3.0, 3.0, 4.0, 4.0,
        ];
        assert_eq!(y, expected);
    }

    #[test]
    fn inference_kernels_equal_the_differentiable_layers() {
        let device = Device::flex();
        let decoder = decoder(&device);
        let x = Tensor::<2>::random([3, 64], Distribution::Normal(0.0, 1.0), &device);
        let (mean, sigma) = decoder.forward_differentiable(x.clone());
        let (fast_mean, fast_sigma) = decoder.forward_inference(x.clone());
        assert_eq!(mean.dims(), [3, 3, 16, 16]);
        let diff = |a: Tensor<4>, b: Tensor<4>| (a - b).abs().max().into_scalar::<f32>();
        assert!(diff(mean, fast_mean) < 1e-5);
        assert!(diff(sigma, fast_sigma) < 1e-5);
    }

    #[test]
    fn training_goes_through_the_differentiable_layers() {
        let device = Device::flex().autodiff();
        let decoder = decoder(&device);
        let x = Tensor::<2>::random([2, 64], Distribution::Normal(0.0, 1.0), &device);
        let (mean, sigma) = decoder.forward(x);
        let grads = (mean.sum() + sigma.sum()).backward();
        for conv in decoder.blocks.iter().chain(&decoder.tail) {
            assert!(conv.weight.grad(&grads).is_some());
        }
        assert!(decoder.sigma.weight.grad(&grads).is_some());
    }
}
