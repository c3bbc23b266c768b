use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

/// Configuration of a [`TimeEmbedding`].
#[derive(Config, Debug)]
pub struct TimeEmbeddingConfig {
    /// Size of the embedding (H).
    #[config(default = 128)]
    pub hidden: usize,
}

/// The attentive model's embedding of a time for attention: queries (target times) and keys
/// (context times). Non-linear (Linear 1 → H, ReLU, Linear H → H), since dot products of a
/// linear embedding such as P(t) are monotonic in the key's time and cannot peak at the
/// query's: attention could only favour the earliest or the latest context.
#[derive(Module, Debug)]
pub struct TimeEmbedding {
    pub hidden: Linear,
    pub output: Linear,
}

impl TimeEmbeddingConfig {
    /// Builds the embedding.
    pub fn init(&self, device: &Device) -> TimeEmbedding {
        TimeEmbedding {
            hidden: super::init::dense(1, self.hidden, device),
            output: super::init::dense(self.hidden, self.hidden, device),
        }
    }
}

impl TimeEmbedding {
    /// `[B, K]` times to `[B, K, H]`.
    pub fn forward(&self, times: Tensor<2>) -> Tensor<3> {
        let x = relu(self.hidden.forward(times.unsqueeze_dim::<3>(2)));
        self.output.forward(x)
    }
}
