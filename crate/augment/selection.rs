use crate::data::{Joints, Normalization};

use super::{Batch, JointTargets};

/// What a [`Sampler`](super::Sampler) draws for one batch, before any frame is read: which
/// sequences, which of their steps at what times, and the blends. Drawing needs only the
/// sequences' lengths, so training can read just the frames a batch holds ([`Pick::frame_steps`])
/// instead of holding a whole dataset in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// N: context slots per sequence.
    pub contexts: usize,
    /// M: targets per sequence.
    pub targets: usize,
    /// M_j: joint-only targets per sequence.
    pub joint_targets: usize,
    /// The B sequences of the batch, in order.
    pub picks: Vec<Pick>,
}

/// One sequence of a [`Selection`].
#[derive(Debug, Clone, PartialEq)]
pub struct Pick {
    /// Index of the sequence in the pool drawn from.
    pub sequence: usize,
    /// Its observed steps (1..=N).
    pub contexts: Vec<Step>,
    /// Its M targets.
    pub targets: Vec<Step>,
    /// Its M_j joint-only targets.
    pub joint_targets: Vec<Step>,
    /// Blending coefficient c.
    pub blend: f32,
}

/// A step of a (time-warped) sequence: the recorded step it shows and its time in the warped
/// sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Index of the recorded step (frame and joints).
    pub index: usize,
    /// Phase in [0, 1].
    pub time: f32,
}

impl Pick {
    /// The recorded steps whose frames the batch holds (contexts and targets), ascending,
    /// each once.
    pub fn frame_steps(&self) -> Vec<usize> {
        let mut steps: Vec<usize> = self
            .contexts
            .iter()
            .chain(&self.targets)
            .map(|s| s.index)
            .collect();
        steps.sort_unstable();
        steps.dedup();
        steps
    }
}

impl Selection {
    /// The batch of `image_size`-pixel frames: `joints(i)` are sequence `i`'s recorded joints,
    /// `frame(i, k)` the RGB bytes of its step `k` (every step of [`Pick::frame_steps`] is
    /// asked for).
    pub fn fill<'a>(
        &self,
        image_size: usize,
        norm: &Normalization,
        joints: impl Fn(usize) -> &'a Joints,
        frame: impl Fn(usize, usize) -> &'a [u8],
    ) -> (Batch, JointTargets) {
        let (b, d) = (self.picks.len(), norm.width());
        let mut batch = Batch::with_targets(b, self.contexts, self.targets, image_size, d);
        let mut joint_targets = JointTargets {
            batch: b,
            targets: self.joint_targets,
            times: Vec::with_capacity(b * self.joint_targets),
            joints: Vec::with_capacity(b * self.joint_targets * d),
        };
        for (b, pick) in self.picks.iter().enumerate() {
            let (i, recorded) = (pick.sequence, joints(pick.sequence));
            for (slot, s) in pick.contexts.iter().enumerate() {
                let values = norm.normalize(&recorded[s.index]);
                batch.set_context(b, slot, frame(i, s.index), &values, s.time);
            }
            for (slot, s) in pick.targets.iter().enumerate() {
                let values = norm.normalize(&recorded[s.index]);
                batch.set_target(b, slot, frame(i, s.index), &values, s.time);
            }
            batch.blend[b] = pick.blend;
            for s in &pick.joint_targets {
                joint_targets.times.push(s.time);
                joint_targets
                    .joints
                    .extend(norm.normalize(&recorded[s.index]));
            }
        }
        (batch, joint_targets)
    }
}
