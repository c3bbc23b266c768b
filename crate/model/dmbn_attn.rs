use burn::module::{Module, Param};
use burn::nn::attention::{MhaInput, MultiHeadAttention, MultiHeadAttentionConfig};
use burn::nn::Linear;
use burn::tensor::{Device, Tensor};

use super::config::check_heads;
use super::context_projection::ContextProjection;
use super::decoder::{Decoder, DecoderConfig};
use super::dmbn_pte::{pte_context_encodings, pte_encoders, PteEncoders};
use super::image_encoder::ImageEncoder;
use super::joint_encoder::JointEncoder;
use super::latent_path::{LatentGaussian, LatentPath, LatentPathConfig};
use super::time_embedding::{TimeEmbedding, TimeEmbeddingConfig};
use super::time_projection::TimeProjection;

use super::{
    AttentiveContexts, BatchTensors, EncodedContexts, ModelConfig, ModelError, ModelKind,
    Prediction, Start,
};

/// The attentive model (`attn`): DMBN-PTE's context encodings, aggregated per target by
/// cross-attention instead of a mean (Kim et al. 2019, "Attentive Neural Processes": a
/// mean-aggregated CNP underfits and misses its own context points):
///
/// - each context: z_m = g_m(e_m(x) + P(t)), as DMBN-PTE;
/// - per target and modality, multi-head attention with the target time's embedding as the
///   query, the contexts' time embeddings as keys and their z_m as values;
/// - blend r_t = c·a_image + (1 − c)·a_joint, then r_t − P(t_target), plus an embedding of
///   which modalities are observed (frames when c > 0, joints when c < 1) and a projection
///   of where the decoders start (the interpolated joints, the gaps to the observations
///   before and after the target), into the same decoders;
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
    /// 9 → H: [`Start::features`] (the interpolated joints and the gaps to the
    /// observations), added to the decoder input.
    pub start_projection: Linear,
    /// Shared layer, image and joint decoders.
    pub decoder: Decoder,
    /// H → D: the joints read from an image context encoding, where the joint decoder starts
    /// when joints are not observed (frames only, as `dmbn imitate` observes). None in files
    /// without it.
    pub frame_joints: Option<Linear>,
    /// The global latent z (`ModelConfig::latent`): what the contexts leave open, drawn once
    /// per sampled future. None in files without it.
    pub latent: Option<LatentPath>,
}

impl DmbnAttn {
    /// Builds the network from the model's config (its kind is not checked: see
    /// [`ModelConfig::init`]); fails on an unsupported image size or a head count that does
    /// not divide H.
    pub fn init(config: &ModelConfig, device: &Device) -> Result<DmbnAttn, ModelError> {
        let (hidden, heads) = (config.hidden, config.attention_heads());
        check_heads(heads, hidden)?;
        let (blocks, tail) = config.image_decoder()?;
        let PteEncoders {
            image_encoder,
            joint_encoder,
            time,
            image_projection,
            joint_projection,
        } = pte_encoders(config, device)?;
        let attention = MultiHeadAttentionConfig::new(hidden, heads).with_dropout(0.0);
        Ok(DmbnAttn {
            image_encoder,
            joint_encoder,
            time,
            image_projection,
            joint_projection,
            time_embedding: TimeEmbeddingConfig::new().with_hidden(hidden).init(device),
            image_attention: attention.init(device),
            joint_attention: attention.init(device),
            observed: Param::from_tensor(Tensor::zeros([2, hidden], device)),
            start_projection: super::init::dense(
                start_features(config.joint_count()),
                hidden,
                device,
            ),
            decoder: starting_at_the_observations(
                DecoderConfig::new(hidden, blocks)
                    .with_joints(config.joint_count())
                    .with_image_tail(tail)
                    .with_image_coarse_tail(config.coarse_tail == Some(true))
                    .with_sigma_floor(config.sigma_floor)
                    .with_gated(true)
                    .init(device),
            ),
            frame_joints: (config.frame_joints == Some(true))
                .then(|| reading_nothing(hidden, config.joint_count(), device)),
            latent: config
                .latent
                .map(|l| LatentPathConfig::new(hidden, l).init(device)),
        })
    }

    /// The network with a latent path of L values ([`DmbnAttn::latent`]) that adds nothing
    /// yet: it predicts as before, and training teaches it (`train --init F --latent L`). A
    /// network that has one keeps it.
    pub fn with_latent_path(mut self, latent: usize, device: &Device) -> DmbnAttn {
        if self.latent.is_none() {
            let hidden = self.start_projection.weight.dims()[1];
            self.latent = Some(LatentPathConfig::new(hidden, latent).init(device));
        }
        self
    }

    /// The network with a joint read-out from frames ([`DmbnAttn::frame_joints`]) that reads
    /// nothing yet (the mean joints): it predicts as before, and training teaches the
    /// read-out. A network that has one keeps it.
    pub fn reading_frame_joints(mut self, device: &Device) -> DmbnAttn {
        if self.frame_joints.is_none() {
            let hidden = self.start_projection.weight.dims()[1];
            let joints = self.decoder.joint.mean.weight.dims()[1];
            self.frame_joints = Some(reading_nothing(hidden, joints, device));
        }
        self
    }
}

/// A read-out `hidden → D` of zeros: joints read as the mean joints (0 normalised), where a
/// model without one starts. Its weights still get gradient, from the encodings it reads.
fn reading_nothing(hidden: usize, joints: usize, device: &Device) -> Linear {
    let mut layer = super::init::dense(hidden, joints, device);
    layer.weight = Param::from_tensor(Tensor::zeros([hidden, joints], device));
    layer
}

impl DmbnAttn {
    /// The batch's contexts encoded one by one, z_m `[B, N, H]` per modality (padding
    /// included), with the observations.
    pub fn encode_set(&self, batch: &BatchTensors) -> EncodedContexts {
        let encodings = pte_context_encodings(
            &self.image_encoder,
            &self.joint_encoder,
            &self.time,
            [&self.image_projection, &self.joint_projection],
            batch,
        );
        EncodedContexts::new(ModelKind::Attn, encodings, batch)
    }

    /// The contexts every target attends to, with `[B]` coefficients c: their encodings,
    /// keys (the embedded times: cheap, so made here rather than kept) and padding. Attention
    /// and the interpolated start read the whole set at each target, in
    /// [`DmbnAttn::condition`].
    pub fn represent(&self, contexts: &EncodedContexts, c: Tensor<1>) -> AttentiveContexts {
        let encodings = contexts.encodings();
        let joints = match &self.frame_joints {
            // The observed joints where joints are observed, those read elsewhere.
            Some(read_out) => {
                let read = read_out.forward(encodings.image.clone());
                let observed = c
                    .clone()
                    .lower_elem(1.0)
                    .float()
                    .unsqueeze_dims::<3>(&[1, 2]);
                contexts.joints().clone() * observed.clone() + read * observed.neg().add_scalar(1.0)
            }
            None => contexts.joints().clone(),
        };
        let prior = self.latent.as_ref().map(|path| {
            path.distribution(
                blended_points(&encodings.image, &encodings.joint, &c),
                contexts.mask().clone(),
            )
        });
        let latent = (self.latent.as_ref())
            .zip(prior.as_ref())
            .map(|(path, prior)| path.project(prior.mean.clone()));
        AttentiveContexts {
            prior,
            latent,
            times: contexts.times().clone(),
            frames: contexts.frames().clone(),
            joints,
            joints_read: self.frame_joints.is_some(),
            image: encodings.image.clone(),
            joint: encodings.joint.clone(),
            keys: self.time_embedding.forward(contexts.times().clone()),
            padding: contexts.mask().clone().equal_elem(0.0),
            blend: c,
        }
    }

    /// The contexts every target attends to, of the batch's contexts.
    pub fn encode(&self, batch: &BatchTensors) -> AttentiveContexts {
        self.represent(&self.encode_set(batch), batch.blend.clone())
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
        let start = Start::new(contexts, &target_times);
        let embedding = start
            .observed()
            .matmul(self.observed.val())
            .unsqueeze_dim::<3>(1);
        let x = r - self.time.forward(target_times)
            + embedding
            + self.start_projection.forward(start.features());
        let x = match &contexts.latent {
            Some(latent) => x + latent.clone().unsqueeze_dim::<3>(1),
            None => x,
        };
        (x, start)
    }

    /// The posterior over z given the contexts and `[B, M]` targets' joints `[B, M, D]`
    /// (normalised), each encoded as an observed joint context: training draws z from it.
    /// None without a latent path.
    pub fn posterior(
        &self,
        contexts: &AttentiveContexts,
        target_times: Tensor<2>,
        target_joints: Tensor<3>,
    ) -> Option<LatentGaussian> {
        let path = self.latent.as_ref()?;
        let [b, m] = target_times.dims();
        let targets = self
            .joint_projection
            .forward(self.joint_encoder.forward(target_joints) + self.time.forward(target_times));
        let observed = blended_points(&contexts.image, &contexts.joint, &contexts.blend);
        let real = contexts.padding.clone().bool_not().float();
        let device = real.device();
        Some(path.distribution(
            Tensor::cat(vec![observed, targets], 1),
            Tensor::cat(vec![real, Tensor::ones([b, m], &device)], 1),
        ))
    }

    /// Encode the contexts and decode the batch's target times.
    pub fn forward(&self, batch: &BatchTensors) -> Prediction {
        let (x, start) = self.condition(&self.encode(batch), batch.target_times.clone());
        self.decoder.forward(x, Some(start))
    }
}

/// Each context's encoding blended as the paper blends the means, c·z_image + (1 − c)·z_joint,
/// `[B, N, H]`: the points the latent path reads.
fn blended_points(image: &Tensor<3>, joint: &Tensor<3>, c: &Tensor<1>) -> Tensor<3> {
    let c = c.clone().unsqueeze_dims::<3>(&[1, 2]);
    image.clone() * c.clone() + joint.clone() * c.neg().add_scalar(1.0)
}

/// Size of [`Start::features`] for `d` joint values: the joints and 2 gaps.
fn start_features(d: usize) -> usize {
    d + 2
}

/// The joint mean head's starting scale against He's: the correction starts small.
const JOINT_CORRECTION_SCALE: f64 = 0.1;

/// A decoder whose joint mean head starts small (a residual branch near nothing; exactly
/// zero would starve the layers below it of gradient): a fresh model predicts about the
/// interpolated joints, and learns the correction. (Its image gate starts half open: the image
/// decoder's `GATE_BIAS`.)
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
