//! How the layers are initialised: He-uniform weights (gain √2, fan-in) and zero biases, for
//! every layer of the encoders and decoders. burn's default (PyTorch's) draws weights with
//! a third of that variance and biases from the same range as the weights; through the
//! joint encoder's seven ReLU layers that shrinks what depends on the input to a small
//! fraction of the constant the biases add, so a fresh encoder barely sees its input and
//! training starts from a representation that ignores the observations. The original Keras
//! model also started from zero biases (Glorot-uniform weights).
use burn::module::Param;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::{Initializer, Linear, LinearConfig, PaddingConfig2d};
use burn::tensor::{Device, Tensor};

/// He-uniform: variance 2 / fan-in, which keeps a ReLU layer's output variance.
const HE: Initializer = Initializer::KaimingUniform {
    gain: std::f64::consts::SQRT_2,
    fan_out_only: false,
};

/// A dense layer `inputs → outputs` with He-uniform weights and a zero bias.
pub fn dense(inputs: usize, outputs: usize, device: &Device) -> Linear {
    let mut layer = LinearConfig::new(inputs, outputs)
        .with_initializer(HE)
        .init(device);
    layer.bias = Some(Param::from_tensor(Tensor::zeros([outputs], device)));
    layer
}

/// A 3x3 'same' convolution `[in, out]` channels with He-uniform weights and a zero bias.
pub fn conv3x3([inputs, outputs]: [usize; 2], device: &Device) -> Conv2d {
    let mut conv = Conv2dConfig::new([inputs, outputs], [3, 3])
        .with_padding(PaddingConfig2d::Same)
        .with_initializer(HE)
        .init(device);
    conv.bias = Some(Param::from_tensor(Tensor::zeros([outputs], device)));
    conv
}
