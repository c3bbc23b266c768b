use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

use super::image_decoder::{ImageDecoder, ImageDecoderConfig};
use super::joint_decoder::{JointDecoder, JointDecoderConfig};
use super::{Prediction, Start};

/// Configuration of a [`Decoder`].
#[derive(Config, Debug)]
pub struct DecoderConfig {
    /// Decoder input per target: H + 1 for DMBN (r and the target time), H for DMBN-PTE.
    pub input: usize,
    /// Width of the shared layer both modality decoders read.
    #[config(default = 1024)]
    pub shared: usize,
    /// Filters of the image decoder's upsampling blocks.
    pub image_filters: Vec<usize>,
    /// Filters of the image decoder's two convolutions at full resolution.
    #[config(default = "super::image_decoder::IMAGE_DECODER_TAIL.to_vec()")]
    pub image_tail: Vec<usize>,
    /// Lower bound of every predicted σ.
    #[config(default = 0.01)]
    pub sigma_floor: f64,
    /// Joint values a step (D).
    #[config(default = 7)]
    pub joints: usize,
    /// A gated image decoder (see [`ImageDecoder`]): the attentive model's.
    #[config(default = false)]
    pub gated: bool,
    /// The image decoder's tail at half resolution (see [`ImageDecoderConfig::coarse_tail`]).
    #[config(default = false)]
    pub image_coarse_tail: bool,
}

/// Both decoders behind their shared Dense 1024 + ReLU layer: one target's conditioned
/// representation to a Gaussian over its frame and its joints.
#[derive(Module, Debug)]
pub struct Decoder {
    /// The shared dense layer.
    pub shared: Linear,
    /// Frame mean and σ.
    pub image: ImageDecoder,
    /// Joint mean and σ.
    pub joint: JointDecoder,
}

impl DecoderConfig {
    /// Builds the decoder.
    pub fn init(&self, device: &Device) -> Decoder {
        Decoder {
            shared: super::init::dense(self.input, self.shared, device),
            image: ImageDecoderConfig::new(self.image_filters.clone())
                .with_tail(self.image_tail.clone())
                .with_input(self.shared)
                .with_sigma_floor(self.sigma_floor)
                .with_gated(self.gated)
                .with_coarse_tail(self.image_coarse_tail)
                .init(device),
            joint: JointDecoderConfig::new()
                .with_input(self.shared)
                .with_joints(self.joints)
                .with_sigma_floor(self.sigma_floor)
                .init(device),
        }
    }
}

impl Decoder {
    /// `[B, M, input]` conditioned representations to the prediction for every target; the
    /// means start from `start` where given (the attentive model).
    pub fn forward(&self, x: Tensor<3>, start: Option<Start>) -> Prediction {
        let [b, m, _] = x.dims();
        let x = self.shared_layer(x);
        let (image_start, joint_start) = start.map(|s| (s.frames(), s.joints())).unzip();
        let frames = self.image.forward(x.clone(), image_start);
        let (joint_mean, joint_sigma) = self.joint.forward(x, joint_start);
        let [_, c, h, w] = frames.mean.dims();
        Prediction {
            image_mean: frames.mean.reshape([b, m, c, h, w]),
            image_sigma: frames.sigma.reshape([b, m, c, h, w]),
            image_drawn: frames.drawn.map(|d| d.reshape([b, m, c, h, w])),
            joint_mean: per_target(joint_mean, b, m),
            joint_sigma: per_target(joint_sigma, b, m),
        }
    }

    /// Only the joints: `[B, M, input]` to their mean and σ, `[B, M, D]` each.
    pub fn joints(&self, x: Tensor<3>, start: Option<Start>) -> (Tensor<3>, Tensor<3>) {
        let [b, m, _] = x.dims();
        let (mean, sigma) = self
            .joint
            .forward(self.shared_layer(x), start.map(|s| s.joints()));
        (per_target(mean, b, m), per_target(sigma, b, m))
    }

    /// The shared Dense + ReLU, `[B, M, input]` to `[B·M, shared]`.
    fn shared_layer(&self, x: Tensor<3>) -> Tensor<2> {
        let [b, m, input] = x.dims();
        relu(self.shared.forward(x.reshape([b * m, input])))
    }
}

/// `[B·M, D]` to `[B, M, D]`.
fn per_target(x: Tensor<2>, b: usize, m: usize) -> Tensor<3> {
    let d = x.dims()[1];
    x.reshape([b, m, d])
}
