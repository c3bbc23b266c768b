/// A training or inference batch as plain arrays (row-major), independent of any tensor
/// library: the sampler fills it, the model turns it into tensors.
///
/// `B` sequences, up to `N` contexts each (padding marked by `context_mask`), `M` targets each.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Batch {
    /// B: sequences in the batch.
    pub batch: usize,
    /// N: context slots per sequence (the largest context count in the batch).
    pub contexts: usize,
    /// M: targets per sequence.
    pub targets: usize,
    /// S: frame width and height.
    pub image_size: usize,
    /// D: joint values a step.
    pub joints: usize,
    /// `[B, N, 3, S, S]`: context frames, RGB scaled to [0, 1], channels first.
    pub context_images: Vec<f32>,
    /// `[B, N, D]`: context joints, normalised with the dataset's statistics.
    pub context_joints: Vec<f32>,
    /// `[B, N]`: context times (phase in [0, 1]).
    pub context_times: Vec<f32>,
    /// `[B, N]`: 1 for a real context, 0 for padding.
    pub context_mask: Vec<f32>,
    /// `[B, M, 3, S, S]`: target frames (empty at inference when only times are given).
    pub target_images: Vec<f32>,
    /// `[B, M, D]`: target joints, normalised (empty at inference).
    pub target_joints: Vec<f32>,
    /// `[B, M]`: target times.
    pub target_times: Vec<f32>,
    /// `[B]`: blending coefficient c: r = c·r_image + (1 − c)·r_joint.
    pub blend: Vec<f32>,
}

impl Batch {
    /// `b` sequences of `n` context slots (padding until [`Batch::set_context`] fills them)
    /// and `m` targets whose frames and joints [`Batch::set_target`] fills: training and
    /// evaluation; frames of `s` pixels a side, `d` joint values a step. Every value zero,
    /// every blend 0.
    pub fn with_targets(b: usize, n: usize, m: usize, s: usize, d: usize) -> Batch {
        let px = 3 * s * s;
        Batch {
            target_images: vec![0.0; b * m * px],
            target_joints: vec![0.0; b * m * d],
            ..Batch::contexts_only(b, n, m, s, d)
        }
    }

    /// [`Batch::with_targets`] without target frames and joints (inference: only the target
    /// times are known, and they are decoded separately).
    pub fn contexts_only(b: usize, n: usize, m: usize, s: usize, d: usize) -> Batch {
        Batch {
            batch: b,
            contexts: n,
            targets: m,
            image_size: s,
            joints: d,
            context_images: vec![0.0; b * n * 3 * s * s],
            context_joints: vec![0.0; b * n * d],
            context_times: vec![0.0; b * n],
            context_mask: vec![0.0; b * n],
            target_images: Vec::new(),
            target_joints: Vec::new(),
            target_times: vec![0.0; b * m],
            blend: vec![0.0; b],
        }
    }

    /// Context slot `i` of sequence `b`: a frame (interleaved RGB bytes, `S × S × 3`), its
    /// normalised joints and its time; the slot becomes real (mask 1).
    pub fn set_context(&mut self, b: usize, i: usize, frame: &[u8], joints: &[f32], time: f32) {
        let slot = b * self.contexts + i;
        let s = self.image_size;
        put(
            s,
            slot,
            frame,
            joints,
            &mut self.context_images,
            &mut self.context_joints,
        );
        self.context_times[slot] = time;
        self.context_mask[slot] = 1.0;
    }

    /// Target `j` of sequence `b` of a batch [`Batch::with_targets`]: its frame, normalised
    /// joints and time.
    pub fn set_target(&mut self, b: usize, j: usize, frame: &[u8], joints: &[f32], time: f32) {
        let slot = b * self.targets + j;
        let s = self.image_size;
        put(
            s,
            slot,
            frame,
            joints,
            &mut self.target_images,
            &mut self.target_joints,
        );
        self.target_times[slot] = time;
    }

    /// `n` batches of `B / n` consecutive sequences each, in order (`n` dividing `B`): a step's
    /// batch shared between devices. Each keeps the N context slots, so the shards' losses
    /// are the batch's, piece by piece.
    pub fn shards(&self, n: usize) -> Vec<Batch> {
        let k = self.batch / n.max(1);
        (0..n)
            .map(|i| {
                let rows = |values: &[f32]| sequences(values, self.batch, i * k..(i + 1) * k);
                Batch {
                    batch: k,
                    context_images: rows(&self.context_images),
                    context_joints: rows(&self.context_joints),
                    context_times: rows(&self.context_times),
                    context_mask: rows(&self.context_mask),
                    target_images: rows(&self.target_images),
                    target_joints: rows(&self.target_joints),
                    target_times: rows(&self.target_times),
                    blend: rows(&self.blend),
                    ..*self
                }
            })
            .collect()
    }

    /// The same contexts with themselves as targets (N targets per sequence, each sequence's
    /// real contexts repeated in order to fill the padding slots): how well a model reproduces
    /// what it observed.
    pub fn contexts_as_targets(&self) -> Batch {
        let (b, n, d) = (self.batch, self.contexts, self.joints);
        let px = 3 * self.image_size * self.image_size;
        let mut out = Batch {
            targets: n,
            target_images: vec![0.0; b * n * px],
            target_joints: vec![0.0; b * n * d],
            target_times: vec![0.0; b * n],
            ..self.clone()
        };
        for s in 0..b {
            let real = self.context_mask[s * n..(s + 1) * n]
                .iter()
                .filter(|&&m| m == 1.0)
                .count()
                .max(1);
            for j in 0..n {
                let (from, to) = (s * n + j % real, s * n + j);
                out.target_images[to * px..(to + 1) * px]
                    .copy_from_slice(&self.context_images[from * px..(from + 1) * px]);
                out.target_joints[to * d..(to + 1) * d]
                    .copy_from_slice(&self.context_joints[from * d..(from + 1) * d]);
                out.target_times[to] = self.context_times[from];
            }
        }
        out
    }
}

/// The values of sequences `range` of a `[B, …]` array of `b` sequences (empty stays empty).
pub(super) fn sequences(values: &[f32], b: usize, range: std::ops::Range<usize>) -> Vec<f32> {
    let per = values.len() / b.max(1);
    values[range.start * per..range.end * per].to_vec()
}

/// One step's frame (`S`-pixel RGB bytes) and joints into slot `slot` of `images` and `values`.
fn put(
    s: usize,
    slot: usize,
    frame: &[u8],
    joints: &[f32],
    images: &mut [f32],
    values: &mut [f32],
) {
    let px = 3 * s * s;
    planar(frame, s, &mut images[slot * px..(slot + 1) * px]);
    let d = joints.len();
    values[slot * d..(slot + 1) * d].copy_from_slice(joints);
}

/// Interleaved RGB bytes (`S × S × 3`) to channels-first floats in [0, 1] (`3 × S × S`).
pub fn planar(rgb: &[u8], s: usize, out: &mut [f32]) {
    let plane = s * s;
    for (p, px) in rgb.chunks_exact(3).enumerate() {
        for c in 0..3 {
            out[c * plane + p] = px[c] as f32 / 255.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::augment::JointTargets;
    use crate::data::JOINTS;

    #[test]
    fn shards_are_the_batch_s_sequences_in_order() {
        let mut batch = Batch::with_targets(4, 2, 3, 2, JOINTS);
        for values in [
            &mut batch.context_images,
            &mut batch.context_joints,
            &mut batch.context_times,
            &mut batch.context_mask,
            &mut batch.target_images,
            &mut batch.target_joints,
            &mut batch.target_times,
            &mut batch.blend,
        ] {
            let per = values.len() / 4;
            for (i, v) in values.iter_mut().enumerate() {
                *v = (i / per) as f32;
            }
        }
        let shards = batch.shards(2);
        assert_eq!(shards.len(), 2);
        for (i, shard) in shards.iter().enumerate() {
            assert_eq!(
                (shard.batch, shard.contexts, shard.targets, shard.image_size),
                (2, 2, 3, 2)
            );
            let first = 2.0 * i as f32;
            assert_eq!(shard.blend, [first, first + 1.0]);
            assert_eq!(shard.context_images.len(), 2 * 2 * 3 * 4);
            assert_eq!(shard.context_images[0], first);
            assert_eq!(*shard.target_joints.last().unwrap(), first + 1.0);
        }
        let join = |f: fn(&Batch) -> &Vec<f32>| -> Vec<f32> {
            shards.iter().flat_map(f).copied().collect()
        };
        assert_eq!(join(|b| &b.context_images), batch.context_images);
        assert_eq!(join(|b| &b.target_times), batch.target_times);
        assert_eq!(batch.shards(1), [batch.clone()]);
        // Inference batches have no target frames: their shards neither.
        assert!(Batch::contexts_only(4, 2, 3, 2, JOINTS).shards(4)[3]
            .target_images
            .is_empty());

        let joints = JointTargets {
            batch: 4,
            targets: 2,
            times: (0..8).map(|i| i as f32).collect(),
            joints: vec![0.0; 8 * JOINTS],
        };
        let shards = joints.shards(2);
        assert_eq!(shards[1].times, [4.0, 5.0, 6.0, 7.0]);
        assert_eq!((shards[1].batch, shards[1].joints.len()), (2, 4 * JOINTS));
        let none = JointTargets {
            batch: 4,
            ..JointTargets::default()
        };
        assert_eq!(none.shards(4)[0].batch, 1);
    }
}
