use burn::config::Config;
use burn::module::Module;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::pool::{MaxPool2d, MaxPool2dConfig};
use burn::nn::{Linear, LinearConfig, PaddingConfig2d};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor};

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
    /// 2x2 max pooling after each convolution.
    pub pool: MaxPool2d,
    /// Flattened 2x2 feature map to the encoding.
    pub dense: Linear,
}

impl ImageEncoderConfig {
    /// Builds the encoder.
    pub fn init(&self, device: &Device) -> ImageEncoder {
        let mut channels = self.channels;
        let convs = self
            .filters
            .iter()
            .map(|&filters| {
                let conv = Conv2dConfig::new([channels, filters], [3, 3])
                    .with_padding(PaddingConfig2d::Same)
                    .init(device);
                channels = filters;
                conv
            })
            .collect();
        ImageEncoder {
            convs,
            pool: MaxPool2dConfig::new([2, 2]).init(),
            dense: LinearConfig::new(channels * 4, self.hidden).init(device),
        }
    }
}

impl ImageEncoder {
    /// `[K, C, S, S]` frames (S = 2^(blocks + 1)) to `[K, H]` encodings.
    pub fn forward(&self, images: Tensor<4>) -> Tensor<2> {
        let mut x = images;
        for conv in &self.convs {
            x = self.pool.forward(relu(conv.forward(x)));
        }
        let [k, c, h, w] = x.dims();
        relu(self.dense.forward(x.reshape([k, c * h * w])))
    }
}
