//! The image networks' layers as operations of burn's autodiff backend, for training: a 3×3
//! 'same' convolution (optionally of the 2× nearest upsampling of its input, with its
//! activation) and 2×2 max pooling on channels-last `[K, H, W, C]` tensors, and the copy of
//! the heads' channels to channels-first frames.
//!
//! burn flex's differentiable `conv2d` is where a training step would spend most of its time
//! (one frame at a time, and the decoder convolves every upsampled map in full). These run
//! forward on the inference kernels of [`FeatureMap`](super::kernels::FeatureMap) and backward
//! on the same patches and products transposed ([`Kernels::input_gradient`],
//! [`Kernels::weight_gradients`]), so training and inference share one implementation. Native
//! only: wasm has no autodiff.
use std::borrow::Cow;
use std::ops::Range;
use std::sync::Arc;

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::NoCheckpointing;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Flex};
use burn::nn::conv::Conv2d;
use burn::tensor::{Tensor, TensorData};

use super::kernels::{max_pool2_gradient, max_pool2_indexed, Activation, Kernels};

/// The autodiff backend training runs on (`Device::flex().autodiff()`).
type Trained = Autodiff<Flex, NoCheckpointing>;

/// Whether `x` lives on the backend these operations run on (flex with autodiff, as
/// `Device::flex().autodiff()` makes); on others (the `cuda` feature) the networks train
/// through burn's own layers.
pub(crate) fn supported<const D: usize>(x: &Tensor<D>) -> bool {
    x.clone().try_into_primitive::<Trained>().is_ok()
}

/// The primitive of a tensor of the training device.
fn primitive<const D: usize>(x: Tensor<D>) -> FloatTensor<Trained> {
    x.try_into_primitive::<Trained>()
        .expect("the image networks train on Device::flex().autodiff()")
}

/// A primitive, contiguous (a copy only if it was not), and its shape: to read its values
/// with [`values`] without copying them.
fn contiguous(x: &FlexTensor) -> (FlexTensor, [usize; 4]) {
    let x = x.to_contiguous();
    let shape = x.layout().shape().to_vec();
    (x, shape4(&shape))
}

/// The values of a contiguous f32 primitive.
fn values(x: &FlexTensor) -> &[f32] {
    x.as_slice::<f32>().expect("contiguous f32 values")
}

fn flex(values: Vec<f32>, shape: [usize; 4]) -> FlexTensor {
    FlexTensor::from_data(TensorData::new(values, shape))
}

fn shape4(shape: &[usize]) -> [usize; 4] {
    shape.try_into().expect("a 4-dimensional map")
}

#[derive(Debug)]
struct Conv3x3Backward;

/// What the gradients need: the input, the output (for the activation's gradient) and the
/// prepared kernels.
#[derive(Clone, Debug)]
struct ConvState {
    input: FlexTensor,
    output: FlexTensor,
    kernels: Arc<Kernels>,
    activation: Activation,
}

impl Backward<Flex, 3> for Conv3x3Backward {
    type State = ConvState;

    fn backward(self, ops: Ops<ConvState, 3>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node_x, node_weight, node_bias] = ops.parents;
        let (grad, grad_shape) = contiguous(&grads.consume::<Flex>(&ops.node));
        let ConvState {
            input,
            output,
            kernels,
            activation,
        } = ops.state;
        // The gradient before the activation.
        let grad: Cow<[f32]> = match activation {
            Activation::Identity => Cow::Borrowed(values(&grad)),
            Activation::Relu => {
                use rayon::prelude::*;
                let pairs = values(&grad).par_iter().zip(values(&output));
                Cow::Owned(
                    pairs
                        .map(|(&g, &y)| if y > 0.0 { g } else { 0.0 })
                        .collect(),
                )
            }
        };
        let shape = shape4(input.layout().shape());
        if let Some(node) = node_x {
            let dx = kernels.input_gradient(&grad, grad_shape);
            grads.register::<Flex>(node.id, flex(dx, shape));
        }
        if node_weight.is_some() || node_bias.is_some() {
            let input = values(&input);
            let (dw, db) = kernels.weight_gradients(input, shape, &grad, grad_shape);
            if let Some(node) = node_weight {
                let shape = [kernels.c_out(), shape[3], 3, 3];
                grads.register::<Flex>(node.id, flex(dw, shape));
            }
            if let Some(node) = node_bias {
                let bias = FlexTensor::from_data(TensorData::new(db, [kernels.c_out()]));
                grads.register::<Flex>(node.id, bias);
            }
        }
    }
}

/// The bias of one of the image networks' convolutions (they all have one).
fn bias(conv: &Conv2d) -> Tensor<1> {
    let bias = conv.bias.as_ref();
    bias.expect("the image networks' convolutions have biases")
        .val()
}

/// [`conv3x3_weights`] with the weights and biases of the 3×3 convolutions `convs`, their
/// outputs side by side as channels (several: one product for all).
pub(crate) fn conv3x3(
    x: Tensor<4>,
    convs: &[&Conv2d],
    upsampled: bool,
    activation: Activation,
) -> Tensor<4> {
    let (weight, bias) = match convs {
        [conv] => (conv.weight.val(), bias(conv)),
        _ => (
            Tensor::cat(convs.iter().map(|c| c.weight.val()).collect(), 0),
            Tensor::cat(convs.iter().map(|c| bias(c)).collect(), 0),
        ),
    };
    conv3x3_weights(x, weight, bias, upsampled, activation)
}

/// `activation(conv3x3(x) + bias)` of the channels-last `[K, H, W, C_in]` map `x` (or of its
/// nearest 2× upsampling, with `upsampled`) for the kernel `weight` `[C_out, C_in, 3, 3]`:
/// `[K, H, W, C_out]` (or `[K, 2H, 2W, C_out]`), differentiable w.r.t. all three inputs.
fn conv3x3_weights(
    x: Tensor<4>,
    weight: Tensor<4>,
    bias: Tensor<1>,
    upsampled: bool,
    activation: Activation,
) -> Tensor<4> {
    let (x, weight, bias) = (primitive(x), primitive(weight), primitive(bias));
    let (input, shape) = contiguous(x.primitive());
    let w = values(&weight.primitive().to_contiguous()).to_vec();
    let b = values(&bias.primitive().to_contiguous()).to_vec();
    let kernels = Arc::new(Kernels::prepare(vec![w], b, shape[3], upsampled));
    let out = kernels.apply(values(&input), shape, activation);
    let output = flex(out.data, out.shape);
    let prepared = Conv3x3Backward
        .prepare::<NoCheckpointing>([x.node(), weight.node(), bias.node()])
        .compute_bound()
        .stateful();
    let y = match prepared {
        OpsKind::Tracked(prep) => {
            let state = ConvState {
                input,
                output: output.clone(),
                kernels,
                activation,
            };
            prep.finish(state, output)
        }
        OpsKind::UnTracked(prep) => prep.finish(output),
    };
    Tensor::from_primitive::<Trained>(y)
}

#[derive(Debug)]
struct MaxPoolBackward;

impl Backward<Flex, 1> for MaxPoolBackward {
    /// Which input each output came from, and the input's shape.
    type State = (Arc<Vec<u8>>, [usize; 4]);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node] = ops.parents;
        let (grad, _) = contiguous(&grads.consume::<Flex>(&ops.node));
        if let Some(node) = node {
            let (from, shape) = ops.state;
            let dx = max_pool2_gradient(values(&grad), &from, shape);
            grads.register::<Flex>(node.id, flex(dx, shape));
        }
    }
}

/// 2×2 max pooling with stride 2 of the channels-last `[K, H, W, C]` map `x`, differentiable.
pub(crate) fn max_pool2(x: Tensor<4>) -> Tensor<4> {
    let x = primitive(x);
    let (input, shape) = contiguous(x.primitive());
    let (out, from) = max_pool2_indexed(values(&input), shape);
    let output = flex(out.data, out.shape);
    let y = match MaxPoolBackward
        .prepare::<NoCheckpointing>([x.node()])
        .compute_bound()
        .stateful()
    {
        OpsKind::Tracked(prep) => prep.finish((Arc::new(from), shape), output),
        OpsKind::UnTracked(prep) => prep.finish(output),
    };
    Tensor::from_primitive::<Trained>(y)
}

/// Channels `channels` of the channels-last `[K, H, W, C]` values `data`, channels-first
/// (`[K, len, H, W]`), or with `back` the reverse: `data` `[K, len, H, W]` into those channels
/// of a zero `[K, H, W, C]` map. In parallel over frames.
fn move_channels(
    data: &[f32],
    [k, h, w, c]: [usize; 4],
    channels: &Range<usize>,
    back: bool,
) -> Vec<f32> {
    use rayon::prelude::*;
    let (len, pixels) = (channels.len(), h * w);
    let mut out = vec![0.0; k * pixels * if back { c } else { len }];
    if k == 0 || pixels == 0 || len == 0 {
        return out;
    }
    let (src_frame, dst_frame) = if back {
        (len * pixels, c * pixels)
    } else {
        (c * pixels, len * pixels)
    };
    out.par_chunks_mut(dst_frame)
        .zip(data.par_chunks(src_frame))
        .for_each(|(dst, src)| {
            for p in 0..pixels {
                for (i, ch) in channels.clone().enumerate() {
                    if back {
                        dst[p * c + ch] = src[i * pixels + p];
                    } else {
                        dst[i * pixels + p] = src[p * c + ch];
                    }
                }
            }
        });
    out
}

#[derive(Debug)]
struct ChannelsFirstBackward;

impl Backward<Flex, 1> for ChannelsFirstBackward {
    /// The input's shape `[K, H, W, C]` and the channels taken.
    type State = ([usize; 4], Range<usize>);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
        let [node] = ops.parents;
        let (grad, _) = contiguous(&grads.consume::<Flex>(&ops.node));
        if let Some(node) = node {
            let (shape, channels) = ops.state;
            let dx = move_channels(values(&grad), shape, &channels, true);
            grads.register::<Flex>(node.id, flex(dx, shape));
        }
    }
}

/// Channels `channels` of the channels-last `[K, H, W, C]` map `x` as a contiguous
/// channels-first `[K, len, H, W]` tensor, differentiable: burn's elementwise operations on a
/// permuted or sliced view (the heads' sigmoid and softplus) are several times slower than on
/// contiguous values.
pub(crate) fn channels_first(x: Tensor<4>, channels: Range<usize>) -> Tensor<4> {
    let x = primitive(x);
    let (input, shape) = contiguous(x.primitive());
    let [k, h, w, c] = shape;
    assert!(channels.end <= c, "channels {channels:?} of {c}");
    let moved = move_channels(values(&input), shape, &channels, false);
    let output = flex(moved, [k, channels.len(), h, w]);
    let y = match ChannelsFirstBackward
        .prepare::<NoCheckpointing>([x.node()])
        .compute_bound()
        .stateful()
    {
        OpsKind::Tracked(prep) => prep.finish((shape, channels), output),
        OpsKind::UnTracked(prep) => prep.finish(output),
    };
    Tensor::from_primitive::<Trained>(y)
}
