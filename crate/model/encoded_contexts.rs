use burn::tensor::{Int, Tensor, TensorData};

use super::{blend, masked_mean, BatchTensors, ContextEncodings, ModelError, ModelKind};

/// A set of observations encoded context by context, before they are aggregated: each
/// context's encoding per modality, with the observations themselves. Every context is encoded
/// on its own, so sets can be joined ([`EncodedContexts::cat`]) and cut
/// ([`EncodedContexts::select`]) without encoding anything again: a live forecast encodes only
/// its new observation. [`Model::represent`](super::Model::represent) aggregates a set into
/// what the decoders take (the set mean, or the contexts the attentive model attends to).
#[derive(Debug, Clone)]
pub struct EncodedContexts {
    /// The kind of the model that encoded them (the encodings mean nothing to another kind).
    kind: ModelKind,
    /// `[B, N, H]` each: the per-context encodings (DMBN: e_m(t, x); the others:
    /// z_m = g_m(e_m(x) + P(t))).
    encodings: ContextEncodings,
    /// `[B, N]`: 1 for a real context, 0 for padding.
    mask: Tensor<2>,
    /// `[B, N]`: context times (phase).
    times: Tensor<2>,
    /// `[B, N, 3, S, S]`: context frames (the attentive model's decoders start from them).
    frames: Tensor<5>,
    /// `[B, N, D]`: context joints, normalised.
    joints: Tensor<3>,
}

impl EncodedContexts {
    /// The encodings of `batch`'s contexts by a `kind` model, with the batch's observations.
    pub(super) fn new(
        kind: ModelKind,
        encodings: ContextEncodings,
        batch: &BatchTensors,
    ) -> EncodedContexts {
        EncodedContexts {
            kind,
            encodings,
            mask: batch.context_mask.clone(),
            times: batch.context_times.clone(),
            frames: batch.context_images.clone(),
            joints: batch.context_joints.clone(),
        }
    }

    /// The kind of the model that encoded them.
    pub fn kind(&self) -> ModelKind {
        self.kind
    }

    /// B: sequences.
    pub fn batch(&self) -> usize {
        self.mask.dims()[0]
    }

    /// N: context slots per sequence (padding included).
    pub fn len(&self) -> usize {
        self.mask.dims()[1]
    }

    /// Never true for a set the model made (every set holds a context).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// H: encoding width.
    pub fn hidden(&self) -> usize {
        self.encodings.image.dims()[2]
    }

    /// S: frame width and height.
    pub fn image_size(&self) -> usize {
        self.frames.dims()[3]
    }

    /// The per-context encodings per modality, `[B, N, H]` each.
    pub fn encodings(&self) -> &ContextEncodings {
        &self.encodings
    }

    /// `[B, N]`: 1 for a real context, 0 for padding.
    pub fn mask(&self) -> &Tensor<2> {
        &self.mask
    }

    /// `[B, N]`: context times.
    pub fn times(&self) -> &Tensor<2> {
        &self.times
    }

    /// The times of the real contexts (padding left out), sequence after sequence.
    pub fn observed_times(&self) -> Vec<f32> {
        let (times, mask) = (
            super::values(self.times.clone()),
            super::values(self.mask.clone()),
        );
        let real = times.iter().zip(&mask).filter(|(_, &m)| m > 0.0);
        real.map(|(&t, _)| t).collect()
    }

    /// `[B, N, 3, S, S]`: context frames.
    pub fn frames(&self) -> &Tensor<5> {
        &self.frames
    }

    /// `[B, N, 7]`: context joints, normalised.
    pub fn joints(&self) -> &Tensor<3> {
        &self.joints
    }

    /// The per-context encodings alone (the time-regression probe's input).
    pub fn into_encodings(self) -> ContextEncodings {
        self.encodings
    }

    /// DMBN's and DMBN-PTE's representation, `[B, H]`: the masked mean over contexts per
    /// modality, blended with each sequence's `[B]` coefficient, r = c·r_image + (1 − c)·r_joint.
    pub fn blended_mean(&self, c: Tensor<1>) -> Tensor<2> {
        let r_image = masked_mean(self.encodings.image.clone(), self.mask.clone());
        let r_joint = masked_mean(self.encodings.joint.clone(), self.mask.clone());
        blend(r_image, r_joint, c)
    }

    /// This set's contexts followed by `other`'s, per sequence: fails unless both come from
    /// models of the same kind, width and frame size and hold as many sequences.
    pub fn cat(&self, other: &EncodedContexts) -> Result<EncodedContexts, ModelError> {
        let describe = |s: &EncodedContexts| {
            format!(
                "a {} model's (H = {}, {}x{} frames, {} sequences)",
                s.kind,
                s.hidden(),
                s.image_size(),
                s.image_size(),
                s.batch()
            )
        };
        let (mine, theirs) = (describe(self), describe(other));
        if mine != theirs {
            return Err(ModelError::Contexts(format!(
                "cannot join {mine} with {theirs}: encode both with the same model"
            )));
        }
        let join = |a: &Tensor<3>, b: &Tensor<3>| Tensor::cat(vec![a.clone(), b.clone()], 1);
        Ok(EncodedContexts {
            kind: self.kind,
            encodings: ContextEncodings {
                image: join(&self.encodings.image, &other.encodings.image),
                joint: join(&self.encodings.joint, &other.encodings.joint),
            },
            mask: Tensor::cat(vec![self.mask.clone(), other.mask.clone()], 1),
            times: Tensor::cat(vec![self.times.clone(), other.times.clone()], 1),
            frames: Tensor::cat(vec![self.frames.clone(), other.frames.clone()], 1),
            joints: join(&self.joints, &other.joints),
        })
    }

    /// The contexts at `indices` (in that order, repeats allowed) of every sequence: fails on
    /// no index or one past the set.
    pub fn select(&self, indices: &[usize]) -> Result<EncodedContexts, ModelError> {
        let n = self.len();
        if indices.is_empty() {
            return Err(ModelError::Contexts(
                "no index to select: expected at least one context".into(),
            ));
        }
        if let Some(i) = indices.iter().find(|&&i| i >= n) {
            return Err(ModelError::Contexts(format!(
                "index {i} is out of range: the set holds {n} contexts"
            )));
        }
        let device = self.mask.device();
        let at = Tensor::<1, Int>::from_data(
            TensorData::new(indices.iter().map(|&i| i as i64).collect(), [indices.len()]),
            &device,
        );
        Ok(EncodedContexts {
            kind: self.kind,
            encodings: ContextEncodings {
                image: self.encodings.image.clone().select(1, at.clone()),
                joint: self.encodings.joint.clone().select(1, at.clone()),
            },
            mask: self.mask.clone().select(1, at.clone()),
            times: self.times.clone().select(1, at.clone()),
            frames: self.frames.clone().select(1, at.clone()),
            joints: self.joints.clone().select(1, at),
        })
    }
}
