use burn::module::Module;
use burn::tensor::{Device, Tensor};

use super::context_projection::{ContextProjection, ContextProjectionConfig};
use super::decoder::{Decoder, DecoderConfig};
use super::image_encoder::{ImageEncoder, ImageEncoderConfig};
use super::joint_encoder::{JointEncoder, JointEncoderConfig};
use super::prediction::per_target;
use super::time_projection::{TimeProjection, TimeProjectionConfig};
use super::{
    BatchTensors, ContextEncodings, EncodedContexts, ModelConfig, ModelError, ModelKind, Prediction,
};

/// DMBN with Positional Time Encoding, "time as context" (the paper's §3.2):
///
/// - encoders see no time: the image encoder reads RGB, the joint encoder the 7 joints;
/// - each context: z_m = g_m(e_m(x) + P(t)), with P a shared Linear 1 → H and g_m a
///   per-modality Linear + LayerNorm + tanh ([`ContextProjection`]);
/// - masked mean over contexts per modality, blend r = c·r_image + (1 − c)·r_joint;
/// - per target, r − P(t_target) (H values, no time concatenated) into the decoders.
#[derive(Module, Debug)]
pub struct DmbnPte {
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
    /// Shared layer, image and joint decoders.
    pub decoder: Decoder,
}

impl DmbnPte {
    /// Builds the network from the model's config (its kind is not checked: see
    /// [`ModelConfig::init`]); fails on an unsupported image size.
    pub fn init(config: &ModelConfig, device: &Device) -> Result<DmbnPte, ModelError> {
        let (blocks, tail) = config.image_decoder()?;
        let PteEncoders {
            image_encoder,
            joint_encoder,
            time,
            image_projection,
            joint_projection,
        } = pte_encoders(config, device)?;
        Ok(DmbnPte {
            image_encoder,
            joint_encoder,
            time,
            image_projection,
            joint_projection,
            decoder: DecoderConfig::new(config.hidden, blocks)
                .with_joints(config.joint_count())
                .with_image_tail(tail)
                .with_image_coarse_tail(config.coarse_tail == Some(true))
                .with_sigma_floor(config.sigma_floor)
                .init(device),
        })
    }

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
        EncodedContexts::new(ModelKind::Pte, encodings, batch)
    }

    /// The blended representation r, `[B, H]`, of encoded contexts with `[B]` coefficients c,
    /// before any target time is subtracted.
    pub fn represent(&self, contexts: &EncodedContexts, c: Tensor<1>) -> Tensor<2> {
        contexts.blended_mean(c)
    }

    /// The blended representation r of the batch's contexts, `[B, H]`.
    pub fn encode(&self, batch: &BatchTensors) -> Tensor<2> {
        self.represent(&self.encode_set(batch), batch.blend.clone())
    }

    /// The decoder input at `[B, M]` target times, `[B, M, H]`: r_target = r − P(t_target).
    pub fn condition(&self, r: &Tensor<2>, target_times: Tensor<2>) -> Tensor<3> {
        per_target(r, target_times.dims()[1]) - self.time.forward(target_times)
    }

    /// Encode the contexts and decode the batch's target times.
    pub fn forward(&self, batch: &BatchTensors) -> Prediction {
        let x = self.condition(&self.encode(batch), batch.target_times.clone());
        self.decoder.forward(x, None)
    }
}

/// DMBN-PTE's context encoders e_image, e_joint, P(t), g_image and g_joint, as DMBN-PTE and
/// the attentive model both build them (each keeps them as its own fields, so that the
/// weights keep their names in the model file).
pub(super) struct PteEncoders {
    pub image_encoder: ImageEncoder,
    pub joint_encoder: JointEncoder,
    pub time: TimeProjection,
    pub image_projection: ContextProjection,
    pub joint_projection: ContextProjection,
}

/// Builds [`PteEncoders`] for the config's frames, image encoder and H; fails on an
/// unsupported image size or encoder.
pub(super) fn pte_encoders(
    config: &ModelConfig,
    device: &Device,
) -> Result<PteEncoders, ModelError> {
    let hidden = config.hidden;
    let projection = ContextProjectionConfig::new().with_hidden(hidden);
    Ok(PteEncoders {
        image_encoder: ImageEncoderConfig::new(3, config.image_encoder()?)
            .with_hidden(hidden)
            .init(device),
        joint_encoder: JointEncoderConfig::new(config.joint_count())
            .with_hidden(hidden)
            .init(device),
        time: TimeProjectionConfig::new().with_hidden(hidden).init(device),
        image_projection: projection.init(device),
        joint_projection: projection.init(device),
    })
}

/// Every context slot's z_m = g_m(e_m(x) + P(t)) per modality, `[B, N, H]` each: the context
/// encoding of DMBN-PTE and of the attentive model, which aggregate it differently.
pub(super) fn pte_context_encodings(
    image_encoder: &ImageEncoder,
    joint_encoder: &JointEncoder,
    time: &TimeProjection,
    [image_projection, joint_projection]: [&ContextProjection; 2],
    batch: &BatchTensors,
) -> ContextEncodings {
    let [b, n, c, s, _] = batch.context_images.dims();
    let images = batch.context_images.clone().reshape([b * n, c, s, s]);
    let image = image_encoder.forward(images);
    let [_, h] = image.dims();
    let time = time.forward(batch.context_times.clone());
    let joint = joint_encoder.forward(batch.context_joints.clone());
    ContextEncodings {
        image: image_projection.forward(image.reshape([b, n, h]) + time.clone()),
        joint: joint_projection.forward(joint + time),
    }
}
