use burn::tensor::Tensor;

/// The blended set representation r of each sequence's contexts: what the decoders are
/// conditioned on. For DMBN-PTE it is r before any target time is subtracted, so one
/// representation serves every target time. Encode once, decode many.
#[derive(Debug, Clone)]
pub struct Representation {
    /// `[B, H]`: r = c·r_image + (1 − c)·r_joint.
    pub r: Tensor<2>,
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
