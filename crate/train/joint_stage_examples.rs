use rand::{Rng, RngExt};

use crate::data::Sequence;
use crate::model::{joint_stage_input_len, joint_stage_inputs, ModelError, JOINT_STAGE_SLOTS};
use crate::predict::{Observations, Predictor};

/// What the joint stage learns from: per target step of a demonstration seen at some
/// glimpses, its inputs ([`joint_stage_inputs`]), the interpolated reads and the true joints.
#[derive(Debug, Clone, Default)]
pub struct JointStageExamples {
    /// D: joint values a step.
    pub joints: usize,
    /// `rows × joint_stage_input_len(D)`.
    pub x: Vec<f32>,
    /// `rows × D`: the reads interpolated at the target.
    pub start: Vec<f32>,
    /// `rows × D`: the demonstration's joints there.
    pub truth: Vec<f32>,
}

impl JointStageExamples {
    /// No examples yet, of `joints` values a step.
    pub fn new(joints: usize) -> Self {
        JointStageExamples {
            joints,
            ..Default::default()
        }
    }

    /// Number of examples (target steps).
    pub fn rows(&self) -> usize {
        self.truth.len() / self.joints.max(1)
    }

    /// Features per example.
    pub fn features(&self) -> usize {
        joint_stage_input_len(self.joints)
    }

    /// Adds `draws` layouts of `seq`: the glimpses, the joints `predictor`'s network reads
    /// from their frames alone, and every step of the demonstration from the first glimpse to
    /// the last as a target (where the stage answers; beyond, the network forecasts).
    pub fn add(
        &mut self,
        predictor: &Predictor,
        seq: &Sequence,
        draws: usize,
        rng: &mut impl Rng,
    ) -> Result<(), ModelError> {
        let t = seq.len();
        if t == 0 {
            return Ok(());
        }
        let phases = seq.times();
        for d in 0..draws {
            let steps = layout(t, d, rng);
            let reads = predictor.reads(&Observations::from_sequence(seq, &steps)?)?;
            let times: Vec<f32> = steps.iter().map(|&s| phases[s]).collect();
            let span = steps[0]..=steps[steps.len() - 1];
            let (x, start) = joint_stage_inputs(&times, &reads, &phases[span.clone()]);
            debug_assert_eq!(x.len(), span.clone().count() * self.features());
            self.x.extend(x);
            self.start.extend(start);
            for k in span {
                self.truth.extend_from_slice(&seq.joints[k]);
            }
        }
        Ok(())
    }
}

/// The `d`-th layout of glimpses of a `t`-step sequence: 2 to [`JOINT_STAGE_SLOTS`] of them (at
/// most t), in turn evenly spaced with the first and last step (as a user observes a whole
/// action), one at a random step of each of as many equal stretches, or evenly spaced over a
/// random prefix of 10-90% (the start of an action, to forecast the rest from).
pub fn layout(t: usize, d: usize, rng: &mut impl Rng) -> Vec<usize> {
    let k = rng.random_range(2..=JOINT_STAGE_SLOTS).min(t);
    if k < 2 {
        return vec![0; t.min(1)];
    }
    let evenly = |k: usize, last: usize| -> Vec<usize> {
        (0..k)
            .map(|i| ((i * last) as f32 / (k - 1) as f32).round() as usize)
            .collect()
    };
    match d % 3 {
        0 => evenly(k, t - 1),
        1 => (0..k)
            .map(|i| rng.random_range(i * t / k..(i + 1) * t / k))
            .collect(),
        _ => {
            let last = ((t - 1) as f32 * rng.random_range(0.1..0.9f32)).round() as usize;
            evenly(k.min(last + 1).max(1), last)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn layouts_hold_two_to_eight_ordered_steps_within_the_sequence() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        for d in 0..200 {
            let t = 5 + d % 150;
            let steps = layout(t, d, &mut rng);
            assert!((1..=JOINT_STAGE_SLOTS).contains(&steps.len()), "{steps:?}");
            assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
            let last = *steps.last().unwrap();
            assert!(last < t);
            match d % 3 {
                0 => assert_eq!((steps[0], last), (0, t - 1)),
                1 => assert!(steps.len() >= 2),
                // A prefix: from the first step to 10-90% of the action.
                _ => assert!(
                    steps[0] == 0 && last * 10 <= 9 * t && (last + 1) * 10 >= t - 1,
                    "{steps:?} of {t}"
                ),
            }
        }
        assert_eq!(layout(1, 0, &mut rng), vec![0]);
    }
}
