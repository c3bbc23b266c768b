use burn::tensor::{Bool, Tensor};

/// What the decoders are conditioned on, computed once per context set so that any number of
/// target times can be decoded from it. Encode once, decode many.
#[derive(Debug, Clone)]
// One value per encoded context set: the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
pub enum Representation {
    /// DMBN and DMBN-PTE: `[B, H]`, the blended mean r = c·r_image + (1 − c)·r_joint (for
    /// DMBN-PTE before any target time is subtracted).
    Mean(Tensor<2>),
    /// The attentive model: the contexts each target attends to.
    Attentive(AttentiveContexts),
}

impl Representation {
    /// B: sequences.
    pub fn batch(&self) -> usize {
        match self {
            Representation::Mean(r) => r.dims()[0],
            Representation::Attentive(contexts) => contexts.blend.dims()[0],
        }
    }
}

/// r repeated for each of `m` targets, `[B, m, H]`.
pub fn per_target(r: &Tensor<2>, m: usize) -> Tensor<3> {
    let [b, h] = r.dims();
    r.clone().unsqueeze_dim::<3>(1).expand([b, m, h])
}

/// The attentive model's context set: per-context encodings of both modalities, the keys
/// (embedded context times), which slots are padding, the blending coefficients, and the
/// observations themselves (what the decoders' means start from).
#[derive(Debug, Clone)]
pub struct AttentiveContexts {
    /// `[B, N]`: context times.
    pub times: Tensor<2>,
    /// `[B, N, 3, S, S]`: context frames.
    pub frames: Tensor<5>,
    /// `[B, N, 7]`: the joints the decoders start from at each context, normalised: the
    /// observed ones where joints are observed (c < 1); elsewhere, for a model that reads them
    /// (`frame_joints`), those read from the context's frame.
    pub joints: Tensor<3>,
    /// Whether `joints` holds joints read from the frames where joints are not observed
    /// (otherwise the decoders start from nothing there).
    pub joints_read: bool,
    /// `[B, N, H]`: image context encodings z_image.
    pub image: Tensor<3>,
    /// `[B, N, H]`: joint context encodings z_joint.
    pub joint: Tensor<3>,
    /// `[B, N, H]`: the embedded context times.
    pub keys: Tensor<3>,
    /// `[B, N]`: true for a padding slot.
    pub padding: Tensor<2, Bool>,
    /// `[B]`: blending coefficient c of each sequence.
    pub blend: Tensor<1>,
    /// A model with a latent path ([`LatentPath`](super::LatentPath)): the prior over z given
    /// these contexts.
    pub prior: Option<super::LatentGaussian>,
    /// `[B, H]`: what z adds to the decoder input (z at the prior's mean, or a drawn z: see
    /// [`Model::with_latent`](super::Model::with_latent)); none without a latent path.
    pub latent: Option<Tensor<2>>,
}

/// The per-context encodings before the set average, per modality: what the paper's
/// time-regression probe reads, and what [`EncodedContexts`](super::EncodedContexts) keeps. For DMBN they are e_m(t, x); for DMBN-PTE
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
    /// `[B, M, 3, S, S]`: the attentive model's own frame before its gate mixes it with the
    /// observed ones (see [`DecodedFrames`](super::DecodedFrames)); none for the others.
    pub image_drawn: Option<Tensor<5>>,
    /// `[B, M, 7]`: mean joints, normalised.
    pub joint_mean: Tensor<3>,
    /// `[B, M, 7]`: σ of every joint, in normalised units.
    pub joint_sigma: Tensor<3>,
}
