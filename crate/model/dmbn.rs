use burn::module::Module;
use burn::tensor::{Device, Tensor};

use super::decoder::{Decoder, DecoderConfig};
use super::image_encoder::{ImageEncoder, ImageEncoderConfig};
use super::joint_encoder::{JointEncoder, JointEncoderConfig};
use super::prediction::per_target;
use super::{
    BatchTensors, ContextEncodings, EncodedContexts, ModelConfig, ModelError, ModelKind, Prediction,
};

/// The original Deep Modality Blending Network, "time as channel" (the paper's §3.1):
///
/// - image encoder on `[t plane, R, G, B]` per context, joint encoder on `(t, 7 joints)`;
/// - masked mean over contexts per modality, blend r = c·r_image + (1 − c)·r_joint;
/// - per target, `[r, t_target]` (H + 1 values) into the shared decoder layer and both
///   decoders.
#[derive(Module, Debug)]
pub struct Dmbn {
    /// e_image, on 4 channels.
    pub image_encoder: ImageEncoder,
    /// e_joint, on 8 values.
    pub joint_encoder: JointEncoder,
    /// Shared layer, image and joint decoders.
    pub decoder: Decoder,
}

impl Dmbn {
    /// Builds the network from the model's config (its kind is not checked: see
    /// [`ModelConfig::init`]); fails on an unsupported image size.
    pub fn init(config: &ModelConfig, device: &Device) -> Result<Dmbn, ModelError> {
        let hidden = config.hidden;
        let (blocks, tail) = config.image_decoder()?;
        Ok(Dmbn {
            image_encoder: ImageEncoderConfig::new(4, config.image_encoder()?)
                .with_hidden(hidden)
                .init(device),
            joint_encoder: JointEncoderConfig::new(config.joint_count() + 1)
                .with_hidden(hidden)
                .init(device),
            decoder: DecoderConfig::new(hidden + 1, blocks)
                .with_joints(config.joint_count())
                .with_image_tail(tail)
                .with_image_coarse_tail(config.coarse_tail == Some(true))
                .with_sigma_floor(config.sigma_floor)
                .init(device),
        })
    }

    /// The batch's contexts encoded one by one, e_m `[B, N, H]` per modality (padding
    /// included), with the observations.
    pub fn encode_set(&self, batch: &BatchTensors) -> EncodedContexts {
        let [b, n, c, s, _] = batch.context_images.dims();
        let times = batch.context_times.clone();
        let plane = times
            .clone()
            .reshape([b, n, 1, 1, 1])
            .expand([b, n, 1, s, s]);
        let images =
            Tensor::cat(vec![plane, batch.context_images.clone()], 2).reshape([b * n, c + 1, s, s]);
        let image = self.image_encoder.forward(images);
        let [_, h] = image.dims();
        let joints = Tensor::cat(
            vec![times.unsqueeze_dim::<3>(2), batch.context_joints.clone()],
            2,
        );
        let encodings = ContextEncodings {
            image: image.reshape([b, n, h]),
            joint: self.joint_encoder.forward(joints),
        };
        EncodedContexts::new(ModelKind::Dmbn, encodings, batch)
    }

    /// The blended representation r, `[B, H]`, of encoded contexts with `[B]` coefficients c.
    pub fn represent(&self, contexts: &EncodedContexts, c: Tensor<1>) -> Tensor<2> {
        contexts.blended_mean(c)
    }

    /// The blended representation r of the batch's contexts, `[B, H]`.
    pub fn encode(&self, batch: &BatchTensors) -> Tensor<2> {
        self.represent(&self.encode_set(batch), batch.blend.clone())
    }

    /// The decoder input at `[B, M]` target times, `[B, M, H + 1]`: `[r, t_target]`.
    pub fn condition(&self, r: &Tensor<2>, target_times: Tensor<2>) -> Tensor<3> {
        let r = per_target(r, target_times.dims()[1]);
        Tensor::cat(vec![r, target_times.unsqueeze_dim::<3>(2)], 2)
    }

    /// Encode the contexts and decode the batch's target times.
    pub fn forward(&self, batch: &BatchTensors) -> Prediction {
        let x = self.condition(&self.encode(batch), batch.target_times.clone());
        self.decoder.forward(x, None)
    }
}
