use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::conv::Conv2d;
use burn::tensor::{Device, Tensor, TensorData};

use super::init::conv3x3;
use super::kernels::FeatureMap;
use super::kernels::{heads, Activation, KernelCache, StartValues};
use super::maps::Maps;
use super::values;
use super::FrameStart;

/// The gate head's starting bias: σ(0) = 1/2 away from the observations, so that the drawn
/// frame gets as much gradient as the copied one (a gate starting nearly open starves it, and
/// a model that only copies cannot forecast what it has not seen).
const GATE_BIAS: f32 = 0.0;

/// Filters of the two convolutions between the last upsampling block and the heads, the
/// original's.
pub const IMAGE_DECODER_TAIL: [usize; 2] = [16, 8];

/// Configuration of an [`ImageDecoder`].
#[derive(Config, Debug)]
pub struct ImageDecoderConfig {
    /// Width of the shared decoder layer it reads, reshaped to `[input / 4, 2, 2]`.
    #[config(default = 1024)]
    pub input: usize,
    /// Filters of the upsampling blocks; each doubles the frame, starting from 2x2.
    pub filters: Vec<usize>,
    /// Filters of the convolutions between the last upsampling block and the heads.
    #[config(default = "IMAGE_DECODER_TAIL.to_vec()")]
    pub tail: Vec<usize>,
    /// Lower bound of the predicted σ.
    #[config(default = 0.01)]
    pub sigma_floor: f64,
    /// With a gate head (the attentive model): the mean mixes its own frame with the frame
    /// it is given to start from, pixel by pixel.
    #[config(default = false)]
    pub gated: bool,
    /// The tail at half resolution: the last block's output is not upsampled, the heads read
    /// the tail's upsampled (the 64x64 work is then only the heads': see
    /// `ModelConfig::coarse_tail`).
    #[config(default = false)]
    pub coarse_tail: bool,
}

/// The image decoder: reshape to 2x2, blocks of Conv 3x3 + ReLU + nearest UpSampling x2,
/// Conv 16 + ReLU, Conv 8 + ReLU (the original's tail; with `coarse_tail` before the last
/// upsampling), then two 3-channel 3x3 heads: the mean (through a sigmoid,
/// since pixels lie in [0, 1]) and σ (see [`crate::model::bounded_sigma`]); gated, a 1-channel gate head g
/// too, and the mean is g·start + (1 − g)·its own with g = n + (1 − n)·σ(gate), n the
/// start's nearness to an observation (g = 1 at an observed step, 0 where the start is not
/// observed): copy what stays as observed, draw what moved.
#[derive(Module, Debug)]
pub struct ImageDecoder {
    /// One 3x3 convolution per upsampling block.
    pub blocks: Vec<Conv2d>,
    /// Conv 16 and Conv 8 at full resolution.
    pub tail: Vec<Conv2d>,
    /// 3-channel mean head.
    pub mean: Conv2d,
    /// 3-channel σ head.
    pub sigma: Conv2d,
    /// 1-channel gate head of a gated decoder.
    pub gate: Option<Conv2d>,
    /// Lower bound of σ.
    pub sigma_floor: f64,
    /// The tail runs at half resolution and the heads read it upsampled.
    pub coarse_tail: bool,
    /// The inference kernels prepared from the convolutions above.
    #[module(skip)]
    pub(crate) kernels: KernelCache,
}

/// What an [`ImageDecoder`] returns for K targets, each `[K, 3, S, S]`.
#[derive(Debug, Clone)]
pub struct DecodedFrames {
    /// The mean frame (gated and given a start: mixed with it).
    pub mean: Tensor<4>,
    /// σ of every pixel channel.
    pub sigma: Tensor<4>,
    /// A gated decoder given a start: the frame it draws itself, before the gate mixes it with
    /// the start (what `train --drawn-frame-weight` supervises on its own).
    pub drawn: Option<Tensor<4>>,
}

impl ImageDecoderConfig {
    /// Builds the decoder.
    pub fn init(&self, device: &Device) -> ImageDecoder {
        let mut channels = self.input / 4;
        let mut layers = |filters: &[usize]| -> Vec<Conv2d> {
            filters
                .iter()
                .map(|&f| {
                    let conv = conv3x3([channels, f], device);
                    channels = f;
                    conv
                })
                .collect()
        };
        let blocks = layers(&self.filters);
        let tail = layers(&self.tail);
        ImageDecoder {
            blocks,
            tail,
            mean: conv3x3([channels, 3], device),
            sigma: conv3x3([channels, 3], device),
            gate: self.gated.then(|| {
                let mut gate = conv3x3([channels, 1], device);
                // `map` keeps the zeros' own (off) gradient tracking: turn it back on, or a
                // fresh model never trains these weights (only a loaded one does).
                gate.weight = gate.weight.map(|w| w.zeros_like()).set_require_grad(true);
                gate.bias = Some(Param::from_tensor(Tensor::full([1], GATE_BIAS, device)));
                gate
            }),
            sigma_floor: self.sigma_floor,
            coarse_tail: self.coarse_tail,
            kernels: KernelCache::default(),
        }
    }
}

impl ImageDecoder {
    /// `[K, input]` to the mean and σ frames, each `[K, 3, S, S]` with S = 2^(blocks + 1).
    /// Training runs the layers as differentiable operations (on flex those of `conv_op`,
    /// elsewhere burn's own layers), inference on the kernels; `Maps` picks the path, and
    /// both of ours fold each upsampling into the convolution that reads it. A gated decoder
    /// mixes its mean with `start` (the attentive model's interpolated observations).
    pub fn forward(&self, x: Tensor<2>, start: Option<FrameStart>) -> DecodedFrames {
        let [k, width] = x.dims();
        let mut maps = Maps::new(x.reshape([k, width / 4, 2, 2]), Some(&self.mean));
        let layers = self.blocks.iter().chain(&self.tail);
        for (i, conv) in layers.enumerate() {
            let upsampled = self.upsampled(i);
            maps = maps.conv3x3(i, &[conv], upsampled, Activation::Relu, &self.kernels);
        }
        // All heads in one product.
        let slot = self.blocks.len() + self.tail.len();
        let heads = self.head_convs();
        let raw = maps.conv3x3(
            slot,
            &heads,
            self.coarse_tail,
            Activation::Identity,
            &self.kernels,
        );
        match raw {
            Maps::Inference(map, device) => self.fused_heads(&map, start, &device),
            #[cfg(not(target_arch = "wasm32"))]
            training => self.heads(training.into_channels_first(&self.head_channels()), start),
        }
    }

    /// [`Self::heads`] at inference, in one pass over the raw outputs (see `kernels::heads`).
    fn fused_heads(
        &self,
        raw: &FeatureMap,
        start: Option<FrameStart>,
        device: &Device,
    ) -> DecodedFrames {
        let [k, h, w, _] = raw.shape;
        let start = start.map(|s| StartValues {
            frames: values(s.frames),
            observed: values(s.observed),
            near: values(s.near),
        });
        let out = heads(
            &raw.data,
            raw.shape,
            self.sigma_floor as f32,
            start.as_ref(),
        );
        let frames = |v| Tensor::from_data(TensorData::new(v, [k, 3, h, w]), device);
        DecodedFrames {
            mean: frames(out.mean),
            sigma: frames(out.sigma),
            drawn: out.drawn.map(frames),
        }
    }

    /// The heads, in the order of their raw outputs: mean, σ, gate.
    fn head_convs(&self) -> Vec<&Conv2d> {
        [&self.mean, &self.sigma]
            .into_iter()
            .chain(&self.gate)
            .collect()
    }

    /// Channels of each head.
    #[cfg(not(target_arch = "wasm32"))]
    fn head_channels(&self) -> Vec<usize> {
        [3, 3]
            .into_iter()
            .chain(self.gate.as_ref().map(|_| 1))
            .collect()
    }

    /// Whether the convolution of layer `i` (blocks, then tail) reads its input upsampled: every
    /// block's output is, but the last one's with a coarse tail (the heads read the tail's).
    fn upsampled(&self, i: usize) -> bool {
        let last = self.blocks.len() - usize::from(self.coarse_tail);
        i > 0 && i <= last
    }

    /// The heads' raw outputs to the mean (sigmoid, mixed with the start by a gated decoder)
    /// and σ frames. A start without a gate, or a gate without a start, leaves the mean alone.
    /// (The training paths': inference runs [`Self::fused_heads`], the same in one pass.)
    #[cfg(not(target_arch = "wasm32"))]
    fn heads(&self, raw: Vec<Tensor<4>>, start: Option<FrameStart>) -> DecodedFrames {
        use super::gaussian::bounded_sigma;
        use burn::tensor::activation::sigmoid;
        let mut raw = raw.into_iter();
        let drawn = sigmoid(raw.next().expect("the mean head"));
        let sigma = bounded_sigma(raw.next().expect("the σ head"), self.sigma_floor);
        match (raw.next(), start) {
            (Some(gate), Some(start)) => {
                // Held open at an observed step, learnt away from the observations.
                let near = start.near;
                let g =
                    (sigmoid(gate) * near.clone().neg().add_scalar(1.0) + near) * start.observed;
                DecodedFrames {
                    mean: start.frames * g.clone() + drawn.clone() * g.neg().add_scalar(1.0),
                    sigma,
                    drawn: Some(drawn),
                }
            }
            _ => DecodedFrames {
                mean: drawn,
                sigma,
                drawn: None,
            },
        }
    }
}

/// Nearest-neighbour upsampling by 2: `[K, C, H, W]` to `[K, C, 2H, 2W]`.
pub fn upsample2(x: Tensor<4>) -> Tensor<4> {
    let [k, c, h, w] = x.dims();
    x.reshape([k, c, h, 1, w, 1])
        .expand([k, c, h, 2, w, 2])
        .reshape([k, c, 2 * h, 2 * w])
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::model::testing::{assert_gradient_close, max_abs, max_abs_diff as diff};
    use burn::tensor::Distribution;

    fn decoder(device: &Device) -> ImageDecoder {
        device.seed(5);
        ImageDecoderConfig::new(vec![16, 8, 8])
            .with_input(64)
            .init(device)
    }

    /// The decoder, and the same weights with the tail at half resolution.
    fn both_tails(device: &Device) -> [ImageDecoder; 2] {
        let fine = decoder(device);
        let coarse = ImageDecoder {
            coarse_tail: true,
            kernels: KernelCache::default(),
            ..fine.clone()
        };
        [fine, coarse]
    }

    #[test]
    fn upsample2_repeats_each_pixel() {
        let device = Device::flex();
        let x = Tensor::<4>::from_floats([[[[1.0, 2.0], [3.0, 4.0]]]], &device);
        let y: Vec<f32> = upsample2(x).into_data().try_to_vec().unwrap();
        #[rustfmt::skip]
        let expected = [
            1.0, 1.0, 2.0, 2.0,
            1.0, 1.0, 2.0, 2.0,
            3.0, 3.0, 4.0, 4.0,
            3.0, 3.0, 4.0, 4.0,
        ];
        assert_eq!(y, expected);
    }

    /// The layers through burn's own operations (upsampling in full): `[K, input]` to the
    /// heads' raw outputs.
    fn forward_burn(decoder: &ImageDecoder, x: Tensor<2>) -> Vec<Tensor<4>> {
        use burn::tensor::activation::relu;
        let [k, width] = x.dims();
        let mut x = x.reshape([k, width / 4, 2, 2]);
        let last = decoder.blocks.len() - 1;
        for (i, conv) in decoder.blocks.iter().enumerate() {
            x = relu(conv.forward(x));
            if i < last || !decoder.coarse_tail {
                x = upsample2(x);
            }
        }
        for conv in &decoder.tail {
            x = relu(conv.forward(x));
        }
        if decoder.coarse_tail {
            x = upsample2(x);
        }
        decoder
            .head_convs()
            .into_iter()
            .map(|conv| conv.forward(x.clone()))
            .collect()
    }

    /// The decoder through burn's own layers: what the other paths must equal.
    fn reference(decoder: &ImageDecoder, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
        let frames = decoder.heads(forward_burn(decoder, x), None);
        (frames.mean, frames.sigma)
    }

    /// Mean and σ of the decoder's own path.
    fn fast(decoder: &ImageDecoder, x: Tensor<2>) -> (Tensor<4>, Tensor<4>) {
        let frames = decoder.forward(x, None);
        (frames.mean, frames.sigma)
    }

    #[test]
    fn inference_equals_burns_layers() {
        let device = Device::flex();
        let x = Tensor::<2>::random([3, 64], Distribution::Normal(0.0, 1.0), &device);
        let [fine, coarse] = both_tails(&device);
        for decoder in [&fine, &coarse] {
            let (mean, sigma) = reference(decoder, x.clone());
            let (fast_mean, fast_sigma) = fast(decoder, x.clone());
            assert_eq!(mean.dims(), [3, 3, 16, 16]);
            assert!(diff(mean, fast_mean) < 1e-5);
            assert!(diff(sigma, fast_sigma) < 1e-5);
        }
        // A coarse tail draws the same frame size from the same weights, differently: its
        // tail's every output covers 2x2 pixels, which the heads' phases tell apart.
        let (fine_mean, _) = fast(&fine, x.clone());
        let (coarse_mean, _) = fast(&coarse, x);
        assert!(diff(fine_mean, coarse_mean.clone()) > 1e-3);
        let m: Vec<f32> = coarse_mean.into_data().try_to_vec().unwrap();
        assert_ne!(
            m[0], m[1],
            "the heads read the upsampled tail per output phase"
        );
    }

    #[test]
    fn gated_paths_equal_burns_layers_and_the_gate_mixes_the_start() {
        for device in [Device::flex(), Device::flex().autodiff()] {
            device.seed(6);
            let mut decoder = ImageDecoderConfig::new(vec![16, 8, 8])
                .with_input(64)
                .with_gated(true)
                .init(&device);
            // A gate that varies from pixel to pixel.
            let gate = decoder.gate.take().unwrap();
            decoder.gate = Some(Conv2d {
                weight: gate
                    .weight
                    .map(|w| w.random_like(Distribution::Normal(0.0, 1.0))),
                ..gate
            });
            let x = Tensor::<2>::random([2, 64], Distribution::Normal(0.0, 1.0), &device);
            let start = FrameStart {
                frames: Tensor::random([2, 3, 16, 16], Distribution::Default, &device),
                observed: Tensor::<1>::from_floats([1.0, 0.0], &device).reshape([2, 1, 1, 1]),
                near: Tensor::<1>::from_floats([0.3, 0.3], &device).reshape([2, 1, 1, 1]),
            };
            let want = decoder.heads(forward_burn(&decoder, x.clone()), Some(start.clone()));
            let got = decoder.forward(x.clone(), Some(start));
            assert!(diff(want.mean.clone(), got.mean) < 1e-5);
            // The drawn frame is the mean a decoder without a start returns.
            let (alone, _) = fast(&decoder, x);
            assert!(diff(got.drawn.expect("a drawn frame"), alone.clone()) < 1e-6);
            // The unobserved target ignores the start; the observed one does not.
            let want = want.mean;
            let row = |t: Tensor<4>, i: usize| t.narrow(0, i, 1);
            assert!(diff(row(want.clone(), 1), row(alone.clone(), 1)) < 1e-6);
            assert!(diff(row(want, 0), row(alone, 0)) > 0.01);
        }
    }

    #[test]
    fn other_autodiff_backends_train_through_burns_layers() {
        // Gradient checkpointing is another autodiff backend than the one conv_op runs on (as
        // the `cuda` feature's device is): training must fall back, not panic.
        let device = Device::flex().autodiff().gradient_checkpointing();
        let decoder = decoder(&device);
        let x = Tensor::<2>::random([2, 64], Distribution::Normal(0.0, 1.0), &device);
        assert!(!super::super::conv_op::supported(&x));
        let (mean, sigma) = fast(&decoder, x.clone());
        let (ref_mean, ref_sigma) = reference(&decoder, x);
        assert!(diff(mean.clone().inner(), ref_mean.inner()) < 1e-6);
        assert!(diff(sigma.inner(), ref_sigma.inner()) < 1e-6);
        let grads = mean.sum().backward();
        assert!(decoder.mean.weight.grad(&grads).is_some());
    }

    #[test]
    fn training_equals_burns_layers_in_values_and_gradients() {
        let device = Device::flex().autodiff();
        for decoder in both_tails(&device) {
            training_equals_burns_layers(&decoder, &device);
        }
    }

    fn training_equals_burns_layers(decoder: &ImageDecoder, device: &Device) {
        let x = Tensor::<2>::random([2, 64], Distribution::Normal(0.0, 1.0), device).require_grad();
        let (mean, sigma) = fast(decoder, x.clone());
        let (ref_mean, ref_sigma) = reference(decoder, x.clone());
        assert!(diff(mean.clone().inner(), ref_mean.clone().inner()) < 1e-5);
        assert!(diff(sigma.clone().inner(), ref_sigma.clone().inner()) < 1e-5);
        // Weighted sums, so that every gradient differs from pixel to pixel.
        let (wm, ws) = (
            mean.random_like(Distribution::Default),
            sigma.random_like(Distribution::Default),
        );
        let loss = |m: Tensor<4>, s: Tensor<4>| (m * wm.clone()).sum() + (s * ws.clone()).sum();
        let grads = loss(mean, sigma).backward();
        let expected = loss(ref_mean, ref_sigma).backward();
        // Each gradient within 1e-4 of its own scale.
        fn close<const D: usize>(got: Option<Tensor<D>>, want: Option<Tensor<D>>) {
            let (got, want) = (got.expect("a gradient"), want.expect("burn's gradient"));
            let scale = max_abs(want.clone());
            assert_gradient_close(got, want, scale);
        }
        let convs = decoder.blocks.iter().chain(&decoder.tail);
        for conv in convs.chain([&decoder.mean, &decoder.sigma]) {
            close(conv.weight.grad(&grads), conv.weight.grad(&expected));
            let bias = conv.bias.as_ref().unwrap();
            close(bias.grad(&grads), bias.grad(&expected));
        }
        close(x.grad(&grads), x.grad(&expected));
    }
}
