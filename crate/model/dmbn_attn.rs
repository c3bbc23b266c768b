use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::attention::{MhaInput, MultiHeadAttention, MultiHeadAttentionConfig};
use burn::tensor::{Device, Tensor};

use super::config::{check_heads, decoder_filters, encoder_filters, ATTENTION_HEADS};
use super::context_projection::{ContextProjection, ContextProjectionConfig};
use super::decoder::{Decoder, DecoderConfig};
use super::dmbn_pte::pte_context_encodings;
use super::image_encoder::{ImageEncoder, ImageEncoderConfig};
use super::interpolation::interpolation_tensors;
use super::joint_encoder::{JointEncoder, JointEncoderConfig};
use super::time_embedding::{TimeEmbedding, TimeEmbeddingConfig};
use super::time_projection::{TimeProjection, TimeProjectionConfig};
use super::{
    AttentiveContexts, BatchTensors, ContextEncodings, FrameStart, JointStart, ModelError,
    Prediction, Start,
};

/// Configuration of a [`DmbnAttn`].
#[derive(Config, Debug)]
pub struct DmbnAttnConfig {
    /// Frame width and height: 64 or 128.
    #[config(default = 64)]
    pub image_size: usize,
    /// Size of the context encodings, of P(t) and of the representation (H).
    #[config(default = 128)]
    pub hidden: usize,
    /// Attention heads (H must be a multiple).
    #[config(default = "ATTENTION_HEADS")]
    pub heads: usize,
    /// Lower bound of every predicted σ.
    #[config(default = 0.01)]
    pub sigma_floor: f64,
}

/// The attentive model (`attn`): DMBN-PTE's context encodings, aggregated per target by
/// cross-attention instead of a mean (Kim et al. 2019, "Attentive Neural Processes": a
/// mean-aggregated CNP underfits and misses its own context points):
///
/// - each context: z_m = g_m(e_m(x) + P(t)), as DMBN-PTE;
/// - per target and modality, multi-head attention with the target time's embedding as the
///   query, the contexts' time embeddings as keys and their z_m as values;
/// - blend r_t = c·a_image + (1 − c)·a_joint, then r_t − P(t_target), plus an embedding of
///   which modalities are observed (frames when c > 0, joints when c < 1), into the same
///   decoders;
/// - the decoders start from the observations linearly interpolated to the target time (held
///   outside them; see [`linear_weights`](super::linear_weights)) for an observed modality,
///   the quality benchmark's trivial baseline: the joint mean is a correction of them, the
///   gated image decoder mixes them pixel by pixel with the frame it draws. The model goes
///   through what it observed and starts where the trivial baselines are; the representation
///   supplies what moved.
#[derive(Module, Debug)]
pub struct DmbnAttn {
    /// e_image, on 3 channels.
    pub image_encoder: ImageEncoder,
    /// e_joint, on 7 values.
    pub joint_encoder: JointEncoder,
    /// P(t), shared by contexts of both modalities and by targets.
    pub time: TimeProjection,
    /// g_image.
    pub image_projection: ContextProjection,
    /// g_joint.
    pub joint_projection: ContextProjection,
    /// Queries and keys: the embedding of target and context times.
    pub time_embedding: TimeEmbedding,
    /// Attention over the image contexts.
    pub image_attention: MultiHeadAttention,
    /// Attention over the joint contexts.
    pub joint_attention: MultiHeadAttention,
    /// `[2, H]`: added to the decoder input when frames (row 0) and joints (row 1) are
    /// observed, so that it knows which means start from observations.
    pub observed: Param<Tensor<2>>,
    /// Shared layer, image and joint decoders.
    pub decoder: Decoder,
}

impl DmbnAttnConfig {
    /// Builds the network; fails on an unsupported image size or a head count that does not
    /// divide H.
    pub fn init(&self, device: &Device) -> Result<DmbnAttn, ModelError> {
        check_heads(self.heads, self.hidden)?;
        let projection = ContextProjectionConfig::new().with_hidden(self.hidden);
        let attention = MultiHeadAttentionConfig::new(self.hidden, self.heads).with_dropout(0.0);
        Ok(DmbnAttn {
            image_encoder: ImageEncoderConfig::new(3, encoder_filters(self.image_size)?)
                .with_hidden(self.hidden)
                .init(device),
            joint_encoder: JointEncoderConfig::new(7)
                .with_hidden(self.hidden)
                .init(device),
            time: TimeProjectionConfig::new()
                .with_hidden(self.hidden)
                .init(device),
            image_projection: projection.init(device),
            joint_projection: projection.init(device),
            time_embedding: TimeEmbeddingConfig::new()
                .with_hidden(self.hidden)
                .init(device),
            image_attention: attention.init(device),
            joint_attention: attention.init(device),
            observed: Param::from_tensor(Tensor::zeros([2, self.hidden], device)),
            decoder: starting_at_the_observations(
                DecoderConfig::new(self.hidden, decoder_filters(self.image_size)?)
                    .with_sigma_floor(self.sigma_floor)
                    .with_gated(true)
                    .init(device),
            ),
        })
    }
}

impl DmbnAttn {
    /// Every context slot's z per modality, `[B, N, H]` each (padding included).
    pub fn encode_contexts(&self, batch: &BatchTensors) -> ContextEncodings {
        pte_context_encodings(
            &self.image_encoder,
            &self.joint_encoder,
            &self.time,
            [&self.image_projection, &self.joint_projection],
            batch,
        )
    }

    /// The contexts every target attends to: their encodings, keys and padding.
    pub fn encode(&self, batch: &BatchTensors) -> AttentiveContexts {
        let encodings = self.encode_contexts(batch);
        let [b, n, c, h, w] = batch.context_images.dims();
        AttentiveContexts {
            times: batch.context_times.clone(),
            frames: batch.context_images.clone().reshape([b, n, c * h * w]),
            joints: batch.context_joints.clone(),
            image: encodings.image,
            joint: encodings.joint,
            keys: self.time_embedding.forward(batch.context_times.clone()),
            padding: batch.context_mask.clone().equal_elem(0.0),
            blend: batch.blend.clone(),
        }
    }

    /// The decoder input at `[B, M]` target times, `[B, M, H]` (per target, attention over
    /// each modality's contexts, blended, minus P(t_target), plus the observed modalities'
    /// embedding), and where the means start.
    pub fn condition(
        &self,
        contexts: &AttentiveContexts,
        target_times: Tensor<2>,
    ) -> (Tensor<3>, Start) {
        let queries = self.time_embedding.forward(target_times.clone());
        let attend = |attention: &MultiHeadAttention, values: &Tensor<3>| {
            let input = MhaInput::new(queries.clone(), contexts.keys.clone(), values.clone())
                .mask_pad(contexts.padding.clone());
            attention.forward(input).context
        };
        let image = attend(&self.image_attention, &contexts.image);
        let joint = attend(&self.joint_attention, &contexts.joint);
        let c = contexts.blend.clone().unsqueeze_dims::<3>(&[1, 2]);
        let r = image * c.clone() + joint * c.neg().add_scalar(1.0);
        let [image_observed, joint_observed] = observed(&contexts.blend);
        let gates = Tensor::stack::<2>(vec![image_observed.clone(), joint_observed.clone()], 1);
        let embedding = gates.matmul(self.observed.val()).unsqueeze_dim::<3>(1);
        let x = r - self.time.forward(target_times.clone()) + embedding;
        let start = self.start(contexts, target_times, image_observed, joint_observed);
        (x, start)
    }

    /// The observations interpolated to the target times, marked or zeroed where their
    /// modality is not observed (`[B]` gates of 1 or 0).
    fn start(
        &self,
        contexts: &AttentiveContexts,
        target_times: Tensor<2>,
        image_observed: Tensor<1>,
        joint_observed: Tensor<1>,
    ) -> Start {
        let [b, m] = target_times.dims();
        let mask = contexts.padding.clone().bool_not().float();
        let (weights, distance) = interpolation_tensors(
            &target_times,
            &contexts.times,
            &mask,
            &target_times.device(),
        );
        let frames = weights.clone().matmul(contexts.frames.clone());
        let joint_observed = joint_observed.unsqueeze_dim::<2>(1);
        let joints =
            weights.matmul(contexts.joints.clone()) * joint_observed.clone().unsqueeze_dim(2);
        // 1 − e^(−d / width) where the joints are observed, else 1.
        let scale = (distance.div_scalar(-OBSERVED_WIDTH).exp() * joint_observed)
            .neg()
            .add_scalar(1.0);
        let s = ((frames.dims()[2] / 3) as f64).sqrt() as usize;
        let observed = image_observed
            .unsqueeze_dim::<2>(1)
            .expand([b, m])
            .reshape([b * m, 1, 1, 1]);
        Start {
            image: FrameStart {
                frames: frames.reshape([b * m, 3, s, s]),
                observed,
            },
            joint: JointStart {
                joints: joints.reshape([b * m, 7]),
                scale: scale.reshape([b * m, 1]),
            },
        }
    }

    /// Encode the contexts and decode the batch's target times.
    pub fn forward(&self, batch: &BatchTensors) -> Prediction {
        let (x, start) = self.condition(&self.encode(batch), batch.target_times.clone());
        self.decoder.forward(x, Some(start))
    }
}

/// Which modalities blend `c` observes, `[B]` gates of 1 or 0 each: frames when c > 0,
/// joints when c < 1.
fn observed(blend: &Tensor<1>) -> [Tensor<1>; 2] {
    [
        blend.clone().greater_elem(0.0).float(),
        blend.clone().lower_elem(1.0).float(),
    ]
}

/// How fast the joint correction fades in away from an observation, in phase: a fifth of it
/// one step of a 100-step action away, 0.63 of it two steps away. At an observed step the
/// model returns the observed joints.
const OBSERVED_WIDTH: f64 = 0.02;

/// The joint mean head's starting scale against He's: the correction starts small.
const JOINT_CORRECTION_SCALE: f64 = 0.1;

/// A decoder whose joint mean head starts small (a residual branch near nothing; exactly
/// zero would starve the layers below it of gradient) and whose image gate starts open: a
/// fresh model predicts about the interpolated observations, and learns the correction.
fn starting_at_the_observations(mut decoder: Decoder) -> Decoder {
    let weight = decoder
        .joint
        .mean
        .weight
        .val()
        .mul_scalar(JOINT_CORRECTION_SCALE)
        .detach();
    decoder.joint.mean.weight = Param::from_tensor(weight);
    decoder
}
