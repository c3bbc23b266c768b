use std::collections::BTreeMap;

use crate::data::Sequence;

/// Phase bins of a [`MeanMotion`].
const BINS: usize = 101;

/// Each action's average motion over phase: the frames and joints of a set of sequences,
/// resampled to common phases and averaged. What a CNP that ignores its observations would
/// predict at best — the baseline that shows whether a model conditions at all.
#[derive(Debug, Clone, PartialEq)]
pub struct MeanMotion {
    frame_len: usize,
    actions: BTreeMap<String, Motion>,
}

#[derive(Debug, Clone, PartialEq)]
struct Motion {
    /// `BINS × frame_len`: mean frames, RGB in [0, 1].
    frames: Vec<f32>,
    /// `BINS × D`: mean joints.
    joints: Vec<Vec<f32>>,
}

impl MeanMotion {
    /// The mean motion of every action among `sequences` (action name, sequence), all of one
    /// frame size and joint count. `None` when there is no sequence or sizes differ.
    pub fn fit<'a>(sequences: impl IntoIterator<Item = (&'a str, &'a Sequence)>) -> Option<Self> {
        // Per action: summed frames, summed joints, sequences.
        type Sums = (Vec<f64>, Vec<Vec<f64>>, usize);
        let mut sums: BTreeMap<String, Sums> = BTreeMap::new();
        let mut frame_len = None;
        for (action, seq) in sequences {
            if seq.is_empty() || *frame_len.get_or_insert(seq.frame_bytes()) != seq.frame_bytes() {
                return None;
            }
            let (n, d) = (seq.frame_bytes(), seq.joints.width());
            let entry = sums
                .entry(action.to_string())
                .or_insert_with(|| (vec![0.0; BINS * n], vec![vec![0.0; d]; BINS], 0));
            if entry.1[0].len() != d {
                return None;
            }
            entry.2 += 1;
            let last = (seq.len() - 1) as f64;
            for bin in 0..BINS {
                let x = bin as f64 / (BINS - 1) as f64 * last;
                let k = x.round() as usize;
                for (sum, &v) in entry.0[bin * n..(bin + 1) * n].iter_mut().zip(seq.frame(k)) {
                    *sum += v as f64 / 255.0;
                }
                let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
                let w = x - lo as f64;
                for j in 0..d {
                    let (a, b) = (seq.joints[lo][j] as f64, seq.joints[hi][j] as f64);
                    entry.1[bin][j] += a + w * (b - a);
                }
            }
        }
        let actions = sums
            .into_iter()
            .map(|(action, (frames, joints, count))| {
                let c = count as f64;
                let motion = Motion {
                    frames: frames.iter().map(|&v| (v / c) as f32).collect(),
                    joints: joints
                        .iter()
                        .map(|row| row.iter().map(|v| (v / c) as f32).collect())
                        .collect(),
                };
                (action, motion)
            })
            .collect();
        Some(MeanMotion {
            frame_len: frame_len?,
            actions,
        })
    }

    /// The mean frame and joints of `action` at `phase` in [0, 1]; `None` for an action the
    /// fit did not see.
    pub fn at(&self, action: &str, phase: f32) -> Option<(&[f32], Vec<f32>)> {
        let motion = self.actions.get(action)?;
        let x = phase.clamp(0.0, 1.0) as f64 * (BINS - 1) as f64;
        let bin = x.round() as usize;
        let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
        let w = (x - lo as f64) as f32;
        let joints = motion.joints[lo]
            .iter()
            .zip(&motion.joints[hi])
            .map(|(a, b)| a + w * (b - a))
            .collect();
        let n = self.frame_len;
        Some((&motion.frames[bin * n..(bin + 1) * n], joints))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;

    fn sequence(len: usize, value: u8, joint: f32) -> Sequence {
        Sequence {
            image_size: 1,
            joints: (0..len).map(|k| [joint * k as f32; JOINTS]).collect(),
            endpoint: Some(vec![[0.0; 7]; len]),
            object: Some(vec![[0.0; 3]; len]),
            frames: vec![value; len * 3],
        }
    }

    #[test]
    fn averages_sequences_of_different_lengths_at_equal_phase() {
        let (a, b) = (sequence(3, 0, 1.0), sequence(5, 255, 0.5));
        let mean = MeanMotion::fit([("grasp", &a), ("grasp", &b)]).unwrap();
        let (frame, joints) = mean.at("grasp", 1.0).unwrap();
        assert!((frame[0] - 0.5).abs() < 1e-6);
        assert!((joints[0] - 2.0).abs() < 1e-6, "both end at 2");
        let (_, joints) = mean.at("grasp", 0.5).unwrap();
        assert!((joints[0] - 1.0).abs() < 1e-6);
        assert!(mean.at("move", 0.5).is_none());
    }
}
