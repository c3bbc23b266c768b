use super::batch::sequences;

/// Extra targets of a [`Batch`](super::Batch) where only the joints are supervised: decoding
/// joints costs a few small layers per target, a frame most of the network, so training
/// scores the joints at many more steps than it decodes frames for.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointTargets {
    /// B: sequences, as the batch.
    pub batch: usize,
    /// M_j: joint-only targets per sequence (0: none).
    pub targets: usize,
    /// `[B, M_j]`: their times.
    pub times: Vec<f32>,
    /// `[B, M_j, D]`: their joints, normalised.
    pub joints: Vec<f32>,
}

impl JointTargets {
    /// `n` sets of `B / n` consecutive sequences' targets each, in order (`n` dividing `B`):
    /// the joint-only targets of [`Batch::shards`](super::Batch::shards)' shards.
    pub fn shards(&self, n: usize) -> Vec<JointTargets> {
        let k = self.batch / n.max(1);
        (0..n)
            .map(|i| {
                let rows = |values: &[f32]| sequences(values, self.batch, i * k..(i + 1) * k);
                JointTargets {
                    batch: k,
                    targets: self.targets,
                    times: rows(&self.times),
                    joints: rows(&self.joints),
                }
            })
            .collect()
    }
}
