use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::PaddingConfig2d;
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Tensor};

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
}

fn conv3x3(channels: [usize; 2], device: &Device) -> Conv2d {
    Conv2dConfig::new(channels, [3, 3])
        .with_padding(PaddingConfig2d::Same)
        .init(device)
}

impl ImageDecoderConfig {
    /// Builds the decoder.
    pub fn init(&self, device: &Device) -> ImageDecoder {
        let mut channels = self.input / 4;
        let mut layers = |filters: &[usize]| -> Vec<Conv2d> {
            filters
                .iter()
                .map(|&f| {
                    let conv = conv3x3([channels, f], device);
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
            mean: conv3x3([channels, 3], device),
            sigma: conv3x3([channels, 3], device),
            sigma_floor: self.sigma_floor,
        }
    }
}

impl ImageDecoder {
    /// `[K, input]` to the mean and σ frames, each `[K, 3, S, S]` with S = 2^(blocks + 1).
    pub fn forward(&self, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
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
}

/// Nearest-neighbour upsampling by 2: `[K, C, H, W]` to `[K, C, 2H, 2W]`.
pub fn upsample2(x: Tensor<4>) -> Tensor<4> {
    let [k, c, h, w] = x.dims();
    x.reshape([k, c, h, 1, w, 1])
        .expand([k, c, h, 2, w, 2])
        .reshape([k, c, 2 * h, 2 * w])
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
