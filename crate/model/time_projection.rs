use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::{Device, Tensor};

/// Configuration of a [`TimeProjection`].
#[derive(Config, Debug)]
pub struct TimeProjectionConfig {
    /// Size of the hidden space (H).
    #[config(default = 128)]
    pub hidden: usize,
}

/// DMBN-PTE's positional time encoding P(t): a one-layer fully connected projection of a
/// time onto the hidden space (Linear 1 → H, no activation), shared by both modalities,
/// added to context encodings and subtracted from the representation per target.
#[derive(Module, Debug)]
pub struct TimeProjection {
    /// The projection.
    pub linear: Linear,
}

impl TimeProjectionConfig {
    /// Builds the projection.
    pub fn init(&self, device: &Device) -> TimeProjection {
        TimeProjection {
            linear: LinearConfig::new(1, self.hidden).init(device),
        }
    }
}

impl TimeProjection {
    /// `[B, K]` times to `[B, K, H]`.
    pub fn forward(&self, times: Tensor<2>) -> Tensor<3> {
        self.linear.forward(times.unsqueeze_dim::<3>(2))
    }
}
