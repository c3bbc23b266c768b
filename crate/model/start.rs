use burn::tensor::Tensor;

use super::interpolation::interpolation_tensors;
use super::AttentiveContexts;

/// How fast the decoders' own predictions fade in away from an observation, in phase: a
/// fifth of the joint correction (and of the drawn frame's free weight) one step of a 100-step
/// action away, 0.63 two steps away. At an observed step the model returns its observations.
const OBSERVED_WIDTH: f64 = 0.02;

/// Where the attentive model's decoders start, per target: its observations linearly
/// interpolated to the target times (see [`linear_weights`](super::linear_weights)), nothing
/// for an unobserved modality (frames are observed when the blend c > 0, joints when c < 1).
/// Each modality's start is computed when its decoder asks ([`Start::frames`],
/// [`Start::joints`]): joint-only targets never interpolate frames.
#[derive(Debug, Clone)]
pub struct Start {
    /// `[B, M, N]`: each context's interpolation weight at each target.
    weights: Tensor<3>,
    /// `[B, M, 2]`: each target's distance to the nearest observation before and after it.
    gaps: Tensor<3>,
    /// `[B, 2]`: 1 where frames (column 0) and joints (column 1) are observed, else 0.
    observed: Tensor<2>,
    /// `[B, 1]`: 1 where the joints start from something (observed, or read from the frames).
    joints_known: Tensor<2>,
    /// `[B, N, 3, S, S]` and `[B, N, 7]`: the observations (the joints: or those read from
    /// the frames, see [`AttentiveContexts::joints`]).
    frames: Tensor<5>,
    joints: Tensor<3>,
}

/// The frames a gated image decoder starts from.
#[derive(Debug, Clone)]
pub struct FrameStart {
    /// `[K, 3, S, S]`: the interpolated context frames.
    pub frames: Tensor<4>,
    /// `[K, 1, 1, 1]`: 1 where frames are observed, else 0 (the gate closes).
    pub observed: Tensor<4>,
    /// `[K, 1, 1, 1]`: e^(−d / width) for the distance d to the nearest observation: 1 at an
    /// observed step, where the gate is held open (the observed frame is returned).
    pub near: Tensor<4>,
}

/// The joints a joint decoder starts from: mean = joints + scale · correction.
#[derive(Debug, Clone)]
pub struct JointStart {
    /// `[K, 7]`: the interpolated context joints, normalised (where not observed: read from
    /// the frames, or 0).
    pub joints: Tensor<2>,
    /// `[K, 1]`: how much of the correction applies: 0 at an observed step, towards 1 away
    /// from the observations (1 where the joints are not observed).
    pub scale: Tensor<2>,
}

impl Start {
    /// The interpolation of `contexts` at `[B, M]` target times.
    pub fn new(contexts: &AttentiveContexts, target_times: &Tensor<2>) -> Start {
        let mask = contexts.padding.clone().bool_not().float();
        let (weights, gaps) =
            interpolation_tensors(target_times, &contexts.times, &mask, &target_times.device());
        let blend = &contexts.blend;
        let observed = Tensor::stack::<2>(
            vec![
                blend.clone().greater_elem(0.0).float(),
                blend.clone().lower_elem(1.0).float(),
            ],
            1,
        );
        let [b, _] = observed.dims();
        let joints_known = if contexts.joints_read {
            Tensor::ones([b, 1], &observed.device())
        } else {
            observed.clone().narrow(1, 1, 1)
        };
        Start {
            weights,
            gaps,
            observed,
            joints_known,
            frames: contexts.frames.clone(),
            joints: contexts.joints.clone(),
        }
    }

    /// `[B, 2]`: 1 where frames (column 0) and joints (column 1) are observed, else 0.
    pub fn observed(&self) -> Tensor<2> {
        self.observed.clone()
    }

    /// What the decoder is told about where it starts, `[B, M, D + 2]`: the interpolated joints
    /// (normalised; read from the frames, or 0, where not observed) and the gaps before and after each target, so that
    /// the correction it adds depends on what it corrects and on how far the observations are.
    pub fn features(&self) -> Tensor<3> {
        Tensor::cat(vec![self.interpolated_joints(), self.gaps.clone()], 2)
    }

    /// The frames at the targets, `[B·M, 3, S, S]`, with where they are observed.
    pub fn frames(&self) -> FrameStart {
        let [b, m, _] = self.weights.dims();
        let [_, n, c, h, w] = self.frames.dims();
        let frames = self
            .weights
            .clone()
            .matmul(self.frames.clone().reshape([b, n, c * h * w]));
        FrameStart {
            frames: frames.reshape([b * m, c, h, w]),
            observed: self.column(0).expand([b, m]).reshape([b * m, 1, 1, 1]),
            near: self.nearness().reshape([b * m, 1, 1, 1]),
        }
    }

    /// The joints at the targets, `[B·M, D]`, and the scale of the correction.
    pub fn joints(&self) -> JointStart {
        let [b, m, _] = self.weights.dims();
        // 1 − e^(−d / width) where the joints are observed, else 1.
        let scale = (self.nearness() * self.column(1)).neg().add_scalar(1.0);
        JointStart {
            joints: self
                .interpolated_joints()
                .reshape([b * m, self.joints.dims()[2]]),
            scale: scale.reshape([b * m, 1]),
        }
    }

    /// `[B, M, D]`: the context joints interpolated to the targets, 0 where there are none.
    fn interpolated_joints(&self) -> Tensor<3> {
        self.weights.clone().matmul(self.joints.clone())
            * self.joints_known.clone().unsqueeze_dim::<3>(2)
    }

    /// `[B, M]`: e^(−d / width), d the distance to the nearest observation.
    fn nearness(&self) -> Tensor<2> {
        let [b, m, _] = self.gaps.dims();
        let [before, after] = [0, 1].map(|i| self.gaps.clone().narrow(2, i, 1));
        before
            .min_pair(after)
            .reshape([b, m])
            .div_scalar(-OBSERVED_WIDTH)
            .exp()
    }

    /// `[B, 1]`: one column of `observed`.
    fn column(&self, i: usize) -> Tensor<2> {
        self.observed.clone().narrow(1, i, 1)
    }
}
