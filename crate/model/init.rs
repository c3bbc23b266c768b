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

/// How a fresh model's weights are drawn: the project's He-uniform (the default), or the
/// original Keras model's Glorot-uniform (`train --initialization glorot`, for the paper's own
/// recipe). Biases are zero either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Initialization {
    /// He-uniform: variance 2 / fan-in.
    #[default]
    He,
    /// Glorot-uniform (Keras' default): variance 2 / (fan-in + fan-out), receptive fields
    /// counted in both fans.
    Glorot,
}

/// `module` with every dense and convolution weight drawn anew from Glorot-uniform (on the
/// module's device, from its seeded generator); biases and other parameters untouched.
pub fn glorot<M: burn::module::Module>(module: M) -> M {
    module.map(&mut Glorot::default())
}

/// Tracks which module a parameter belongs to, so that only the weights of `Linear` and
/// `Conv2d` layers are redrawn.
#[derive(Default)]
struct Glorot {
    path: Vec<(String, String)>,
}

impl burn::module::ModuleMapper for Glorot {
    fn enter_module(&mut self, name: &str, container_type: &str) {
        self.path
            .push((name.to_string(), container_type.to_string()));
    }

    fn exit_module(&mut self, _name: &str, _container_type: &str) {
        self.path.pop();
    }

    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        // The last entry is the parameter's field and the layer that holds it.
        let (field, layer) = match self.path.last() {
            Some((field, layer)) => (field.as_str(), Some(layer.as_str())),
            None => ("", None),
        };
        let is_weight = field == "weight";
        let fans = |dims: &[usize]| match (layer, dims) {
            // burn's Linear weight is [in, out].
            (Some("Struct:Linear"), [inputs, outputs]) => Some((*inputs, *outputs)),
            // Conv2d: [out, in, kh, kw].
            (Some("Struct:Conv2d"), [out, inputs, kh, kw]) => {
                Some((inputs * kh * kw, out * kh * kw))
            }
            _ => None,
        };
        let dims = param.val().shape().dims::<D>().to_vec();
        let Some((fan_in, fan_out)) = fans(&dims).filter(|_| is_weight) else {
            return param;
        };
        let limit = (6.0 / (fan_in + fan_out) as f64).sqrt();
        let uniform = burn::tensor::Distribution::Uniform(-limit, limit);
        // A fresh tensor does not track gradients: the weight must, to be trained.
        param
            .map(|w| Tensor::random(w.shape(), uniform, &w.device()))
            .set_require_grad(true)
    }
}
