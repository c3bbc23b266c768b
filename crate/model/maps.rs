//! The image networks' layers behind one entry point: the feature maps between layers are
//! held in the representation of the path that runs them, chosen once as they enter the
//! network, so that a network's `forward` names each layer once.
use burn::nn::conv::Conv2d;
use burn::tensor::{Device, Tensor};

use super::kernels::{Activation, FeatureMap, KernelCache};

/// A stack of K feature maps between two layers of an image network.
#[derive(Debug)]
pub(crate) enum Maps {
    /// Inference (always in wasm): channels-last values for the kernels, and the device the
    /// tensors they end in go to.
    Inference(FeatureMap, Device),
    /// Training on flex autodiff: a channels-last `[K, H, W, C]` tensor for the operations of
    /// `conv_op`.
    #[cfg(not(target_arch = "wasm32"))]
    Autodiff(Tensor<4>),
    /// Training on other backends (the `cuda` feature, gradient checkpointing): a
    /// channels-first `[K, C, H, W]` tensor for burn's own layers.
    #[cfg(not(target_arch = "wasm32"))]
    Burn(Tensor<4>),
}

impl Maps {
    /// The channels-first `[K, C, H, W]` maps `x` entering a network with the convolution
    /// `conv`: for training when either takes part in an autodiff graph (it is trained, or
    /// computed from what is), else for the inference kernels.
    pub(crate) fn new(x: Tensor<4>, conv: Option<&Conv2d>) -> Self {
        #[cfg(not(target_arch = "wasm32"))]
        if x.is_tracked() || conv.is_some_and(|c| c.weight.val().is_tracked()) {
            return if super::conv_op::supported(&x) {
                Maps::Autodiff(x.permute([0, 2, 3, 1]))
            } else {
                Maps::Burn(x)
            };
        }
        #[cfg(target_arch = "wasm32")]
        let _ = conv;
        let device = x.device();
        Maps::Inference(FeatureMap::from_channels_first(x), device)
    }

    /// The 3×3 'same' convolutions `convs` (their outputs side by side as channels) of these
    /// maps or, with `upsampled`, of their nearest 2× upsampling, followed by `activation`.
    /// The inference kernels are kept in `slot` of `cache`; the convolution of an upsampled
    /// map reads the low-resolution one, except through burn's layers.
    pub(crate) fn conv3x3(
        self,
        slot: usize,
        convs: &[&Conv2d],
        upsampled: bool,
        activation: Activation,
        cache: &KernelCache,
    ) -> Self {
        match self {
            Maps::Inference(map, device) => {
                let kernels = cache.get(slot, convs, map.shape[3], upsampled);
                Maps::Inference(map.conv3x3(&kernels, activation), device)
            }
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Autodiff(x) => {
                Maps::Autodiff(super::conv_op::conv3x3(x, convs, upsampled, activation))
            }
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Burn(x) => {
                let x = if upsampled { super::upsample2(x) } else { x };
                let y = match convs {
                    [conv] => conv.forward(x),
                    _ => Tensor::cat(convs.iter().map(|c| c.forward(x.clone())).collect(), 1),
                };
                Maps::Burn(match activation {
                    Activation::Identity => y,
                    Activation::Relu => burn::tensor::activation::relu(y),
                })
            }
        }
    }

    /// 2×2 max pooling with stride 2.
    pub(crate) fn max_pool2(self) -> Self {
        match self {
            Maps::Inference(map, device) => Maps::Inference(map.max_pool2(), device),
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Autodiff(x) => Maps::Autodiff(super::conv_op::max_pool2(x)),
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Burn(x) => {
                let pool = burn::nn::pool::MaxPool2dConfig::new([2, 2]).init();
                Maps::Burn(pool.forward(x))
            }
        }
    }

    /// Channels of each map.
    pub(crate) fn channels(&self) -> usize {
        match self {
            Maps::Inference(map, _) => map.shape[3],
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Autodiff(x) => x.dims()[3],
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Burn(x) => x.dims()[1],
        }
    }

    /// Channels-first tensors of consecutive channel groups of `sizes` channels, each
    /// `[K, size, H, W]`: what the layers after the convolutions read.
    pub(crate) fn into_channels_first(self, sizes: &[usize]) -> Vec<Tensor<4>> {
        match self {
            Maps::Inference(map, device) => map.into_channels_first(sizes, &device),
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Autodiff(x) => {
                let mut first = 0;
                sizes
                    .iter()
                    .map(|&size| {
                        first += size;
                        super::conv_op::channels_first(x.clone(), first - size..first)
                    })
                    .collect()
            }
            #[cfg(not(target_arch = "wasm32"))]
            Maps::Burn(x) => match sizes {
                [_] => vec![x],
                _ => x.split_with_sizes(sizes.to_vec(), 1),
            },
        }
    }
}
