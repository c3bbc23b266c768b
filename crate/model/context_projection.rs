use burn::config::Config;
use burn::module::Module;
use burn::nn::{LayerNorm, LayerNormConfig, Linear};
use burn::tensor::{Device, Tensor};

/// Configuration of a [`ContextProjection`].
#[derive(Config, Debug)]
pub struct ContextProjectionConfig {
    /// Size of the hidden space (H).
    #[config(default = 128)]
    pub hidden: usize,
}

/// DMBN-PTE's per-modality non-linear projection g_m of `e_m(x) + P(t)` onto the same space:
/// Linear H → H, LayerNorm, tanh.
///
/// LayerNorm puts every context on the same scale, so no context dominates the set average
/// and the time component keeps its weight after averaging; tanh (rather than ReLU) keeps
/// both signs of the normalised features, so no half of them is zeroed, and bounds them.
#[derive(Module, Debug)]
pub struct ContextProjection {
    /// H → H.
    pub linear: Linear,
    /// Normalisation over the H features.
    pub norm: LayerNorm,
}

impl ContextProjectionConfig {
    /// Builds the projection.
    pub fn init(&self, device: &Device) -> ContextProjection {
        ContextProjection {
            linear: super::init::dense(self.hidden, self.hidden, device),
            norm: LayerNormConfig::new(self.hidden).init(device),
        }
    }
}

impl ContextProjection {
    /// `[B, N, H]` to `[B, N, H]`.
    pub fn forward(&self, x: Tensor<3>) -> Tensor<3> {
        self.norm.forward(self.linear.forward(x)).tanh()
    }
}
