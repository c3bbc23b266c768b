use burn::tensor::Tensor;

use super::{blend, masked_mean, BatchTensors};

/// The blended set representation r of each sequence's contexts: what the decoders are
/// conditioned on. For DMBN-PTE it is r before any target time is subtracted, so one
/// representation serves every target time. Encode once, decode many.
#[derive(Debug, Clone)]
pub struct Representation {
    /// `[B, H]`: r = c·r_image + (1 − c)·r_joint.
    pub r: Tensor<2>,
}

impl Representation {
    /// r repeated for each of `m` targets, `[B, m, H]`.
    pub fn per_target(&self, m: usize) -> Tensor<3> {
        let [b, h] = self.r.dims();
        self.r.clone().unsqueeze_dim::<3>(1).expand([b, m, h])
    }
}

/// The per-context encodings before the set average, per modality: what the paper's
/// time-regression probe reads. For DMBN they are e_m(t, x); for DMBN-PTE
/// z = g_m(e_m(x) + P(t)). Padding slots are included (mask them out).
#[derive(Debug, Clone)]
pub struct ContextEncodings {
    /// `[B, N, H]`: image context encodings.
    pub image: Tensor<3>,
    /// `[B, N, H]`: joint context encodings.
    pub joint: Tensor<3>,
}

impl ContextEncodings {
    /// The set representation of both networks: the masked mean over contexts per modality,
    /// blended with each sequence's coefficient, r = c·r_image + (1 − c)·r_joint.
    pub fn represent(self, batch: &BatchTensors) -> Representation {
        let r_image = masked_mean(self.image, batch.context_mask.clone());
        let r_joint = masked_mean(self.joint, batch.context_mask.clone());
        Representation {
            r: blend(r_image, r_joint, batch.blend.clone()),
        }
    }
}

/// A diagonal Gaussian over each target's frame and joints.
#[derive(Debug, Clone)]
pub struct Prediction {
    /// `[B, M, 3, S, S]`: mean frame, in [0, 1].
    pub image_mean: Tensor<5>,
    /// `[B, M, 3, S, S]`: σ of every pixel channel.
    pub image_sigma: Tensor<5>,
    /// `[B, M, 7]`: mean joints, normalised.
    pub joint_mean: Tensor<3>,
    /// `[B, M, 7]`: σ of every joint, in normalised units.
    pub joint_sigma: Tensor<3>,
}
