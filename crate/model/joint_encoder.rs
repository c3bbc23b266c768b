use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

/// Widths of the joint encoder's hidden layers (the original DMBN's).
pub const JOINT_ENCODER_LAYERS: [usize; 6] = [32, 64, 64, 128, 128, 256];

/// Configuration of a [`JointEncoder`].
#[derive(Config, Debug)]
pub struct JointEncoderConfig {
    /// Input values per context: 8 for DMBN (t, then 7 joints), 7 for DMBN-PTE.
    pub inputs: usize,
    /// Size of the encoding (H).
    #[config(default = 128)]
    pub hidden: usize,
}

/// The per-context joint encoder e_joint: Dense 32, 64, 64, 128, 128, 256, then Dense H,
/// all ReLU.
#[derive(Module, Debug)]
pub struct JointEncoder {
    /// The dense layers, input to encoding.
    pub layers: Vec<Linear>,
}

impl JointEncoderConfig {
    /// Builds the encoder.
    pub fn init(&self, device: &Device) -> JointEncoder {
        let mut inputs = self.inputs;
        let layers = JOINT_ENCODER_LAYERS
            .iter()
            .chain([self.hidden].iter())
            .map(|&width| {
                let layer = super::init::dense(inputs, width, device);
                inputs = width;
                layer
            })
            .collect();
        JointEncoder { layers }
    }
}

impl JointEncoder {
    /// `[..., inputs]` to `[..., H]`.
    pub fn forward<const D: usize>(&self, joints: Tensor<D>) -> Tensor<D> {
        self.layers
            .iter()
            .fold(joints, |x, layer| relu(layer.forward(x)))
    }
}
