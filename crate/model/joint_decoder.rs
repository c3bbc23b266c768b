use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

use super::gaussian::bounded_sigma;
use super::JointStart;

/// Widths of the joint decoder's hidden layers (the original DMBN's).
pub const JOINT_DECODER_LAYERS: [usize; 4] = [512, 216, 128, 32];

/// Configuration of a [`JointDecoder`].
#[derive(Config, Debug)]
pub struct JointDecoderConfig {
    /// Width of the shared decoder layer it reads.
    #[config(default = 1024)]
    pub input: usize,
    /// Lower bound of the predicted σ.
    #[config(default = 0.01)]
    pub sigma_floor: f64,
    /// Joint values a step (D): the heads' width.
    #[config(default = 7)]
    pub joints: usize,
}

/// The joint decoder: Dense 512, 216, 128, 32 (ReLU), then two linear Dense D heads: the
/// mean (normalised joints) and σ (see [`bounded_sigma`]).
#[derive(Module, Debug)]
pub struct JointDecoder {
    /// The hidden dense layers.
    pub layers: Vec<Linear>,
    /// D-value mean head.
    pub mean: Linear,
    /// D-value σ head.
    pub sigma: Linear,
    /// Lower bound of σ.
    pub sigma_floor: f64,
}

impl JointDecoderConfig {
    /// Builds the decoder.
    pub fn init(&self, device: &Device) -> JointDecoder {
        let mut inputs = self.input;
        let layers = JOINT_DECODER_LAYERS
            .iter()
            .map(|&width| {
                let layer = super::init::dense(inputs, width, device);
                inputs = width;
                layer
            })
            .collect();
        JointDecoder {
            layers,
            mean: super::init::dense(inputs, self.joints, device),
            sigma: super::init::dense(inputs, self.joints, device),
            sigma_floor: self.sigma_floor,
        }
    }
}

impl JointDecoder {
    /// `[K, input]` to the mean and σ joints, each `[K, 7]`; given a `start` (the attentive
    /// model's interpolated observations), the mean is a scaled correction of it.
    pub fn forward(&self, x: Tensor<2>, start: Option<JointStart>) -> (Tensor<2>, Tensor<2>) {
        let x = self
            .layers
            .iter()
            .fold(x, |x, layer| relu(layer.forward(x)));
        let mean = self.mean.forward(x.clone());
        let mean = match start {
            Some(start) => start.joints + mean * start.scale,
            None => mean,
        };
        let sigma = bounded_sigma(self.sigma.forward(x), self.sigma_floor);
        (mean, sigma)
    }
}
