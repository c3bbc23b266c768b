use serde::{Deserialize, Serialize};

use super::is_object;
use crate::data::JOINTS;

/// Arm joints (radians) among the [`JOINTS`] values; the last one is the gripper.
const ARM: usize = JOINTS - 1;

/// Sums of errors over the steps of one or more sequences, pooled so that every step weighs
/// the same; [`Accumulator::finish`] turns them into a [`Quality`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Accumulator {
    sequences: usize,
    steps: usize,
    joint_se: f64,
    gripper_ae: f64,
    image_se: f64,
    image_values: usize,
    observed_steps: usize,
    observed_joint_se: f64,
    observed_image_se: f64,
    observed_image_values: usize,
    image_nll: f64,
    joint_nll: f64,
    nll_steps: usize,
    object_intersection: usize,
    object_union: usize,
    observed_object_intersection: usize,
    observed_object_union: usize,
}

/// One guess at one step: the mean frame (interleaved RGB in [0, 1]) and joints (dataset
/// units), with σ when the guess is a model's prediction.
#[derive(Debug, Clone, Copy)]
pub struct Guess<'a> {
    pub frame: &'a [f32],
    pub joints: &'a [f32],
    /// σ of every pixel channel and every joint, and the joints' standard deviations (NLL is
    /// per value in normalised joint units, as in training).
    pub sigma: Option<(&'a [f32], &'a [f32], &'a [f32; JOINTS])>,
}

/// The benchmark's measures of one model or baseline over a set of sequences.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// Sequences scored.
    pub sequences: usize,
    /// Scored steps over all sequences.
    pub steps: usize,
    /// Root mean squared error of the 6 arm joints over the scored steps, radians.
    pub joint_rmse: f64,
    /// Mean absolute error of the gripper value over the scored steps (dataset units).
    pub gripper_mae: f64,
    /// Mean squared error of the frames over the scored steps, pixels in [0, 1].
    pub image_mse: f64,
    /// Joint RMSE (radians, arm joints) at the observed steps themselves.
    pub observed_joint_rmse: f64,
    /// Image MSE at the observed steps themselves.
    pub observed_image_mse: f64,
    /// Gaussian NLL per pixel value over the scored steps (models only).
    pub image_nll: Option<f64>,
    /// Gaussian NLL per joint value, normalised units, over the scored steps (models only).
    pub joint_nll: Option<f64>,
    /// Overlap (intersection over union, pooled over steps) of the object's colour mask in the
    /// guessed frames with the true frames' mask, over the scored steps; `None` when the
    /// object is never visible in either.
    pub object_iou: Option<f64>,
    /// The same overlap at the observed steps.
    pub observed_object_iou: Option<f64>,
}

impl Accumulator {
    /// Counts one more sequence.
    pub fn begin_sequence(&mut self) {
        self.sequences += 1;
    }

    /// Adds one step's guess against the true `frame` (RGB bytes) and `joints`; `observed`
    /// steps go to the observed-step measures, `scored` ones to the rest (a step can be both).
    pub fn add(
        &mut self,
        guess: Guess,
        frame: &[u8],
        joints: &[f32; JOINTS],
        observed: bool,
        scored: bool,
    ) {
        let joint_se: f64 = (0..ARM)
            .map(|j| (guess.joints[j] as f64 - joints[j] as f64).powi(2))
            .sum();
        let image_se: f64 = frame
            .iter()
            .zip(guess.frame)
            .map(|(&x, &m)| (x as f64 / 255.0 - m as f64).powi(2))
            .sum();
        let (intersection, union) = object_overlap(guess.frame, frame);
        if observed {
            self.observed_steps += 1;
            self.observed_joint_se += joint_se;
            self.observed_image_se += image_se;
            self.observed_image_values += frame.len();
            self.observed_object_intersection += intersection;
            self.observed_object_union += union;
        }
        if !scored {
            return;
        }
        self.steps += 1;
        self.joint_se += joint_se;
        self.gripper_ae += (guess.joints[ARM] as f64 - joints[ARM] as f64).abs();
        self.image_se += image_se;
        self.image_values += frame.len();
        self.object_intersection += intersection;
        self.object_union += union;
        if let Some((image_sigma, joint_sigma, std)) = guess.sigma {
            self.nll_steps += 1;
            self.image_nll += frame
                .iter()
                .zip(guess.frame)
                .zip(image_sigma)
                .map(|((&x, &m), &s)| nll(x as f64 / 255.0, m as f64, s as f64))
                .sum::<f64>()
                / frame.len() as f64;
            self.joint_nll += (0..JOINTS)
                .map(|j| {
                    let std = std[j] as f64;
                    nll(
                        joints[j] as f64 / std,
                        guess.joints[j] as f64 / std,
                        joint_sigma[j] as f64 / std,
                    )
                })
                .sum::<f64>()
                / JOINTS as f64;
        }
    }

    /// Adds another accumulator's sums (another set of sequences).
    pub fn merge(&mut self, other: &Accumulator) {
        self.sequences += other.sequences;
        self.steps += other.steps;
        self.joint_se += other.joint_se;
        self.gripper_ae += other.gripper_ae;
        self.image_se += other.image_se;
        self.image_values += other.image_values;
        self.observed_steps += other.observed_steps;
        self.observed_joint_se += other.observed_joint_se;
        self.observed_image_se += other.observed_image_se;
        self.observed_image_values += other.observed_image_values;
        self.image_nll += other.image_nll;
        self.joint_nll += other.joint_nll;
        self.nll_steps += other.nll_steps;
        self.object_intersection += other.object_intersection;
        self.object_union += other.object_union;
        self.observed_object_intersection += other.observed_object_intersection;
        self.observed_object_union += other.observed_object_union;
    }

    /// The measures; NaN where nothing was counted.
    pub fn finish(&self) -> Quality {
        let div = |a: f64, n: usize| if n == 0 { f64::NAN } else { a / n as f64 };
        let iou = |i: usize, u: usize| (u > 0).then(|| i as f64 / u as f64);
        Quality {
            sequences: self.sequences,
            steps: self.steps,
            joint_rmse: div(self.joint_se, self.steps * ARM).sqrt(),
            gripper_mae: div(self.gripper_ae, self.steps),
            image_mse: div(self.image_se, self.image_values),
            observed_joint_rmse: div(self.observed_joint_se, self.observed_steps * ARM).sqrt(),
            observed_image_mse: div(self.observed_image_se, self.observed_image_values),
            image_nll: (self.nll_steps > 0).then(|| self.image_nll / self.nll_steps as f64),
            joint_nll: (self.nll_steps > 0).then(|| self.joint_nll / self.nll_steps as f64),
            object_iou: iou(self.object_intersection, self.object_union),
            observed_object_iou: iou(
                self.observed_object_intersection,
                self.observed_object_union,
            ),
        }
    }
}

/// Pixels of the object's colour in both frames, and in either.
fn object_overlap(guess: &[f32], truth: &[u8]) -> (usize, usize) {
    let (mut intersection, mut union) = (0, 0);
    for (g, t) in guess.chunks_exact(3).zip(truth.chunks_exact(3)) {
        let a = is_object(g[0], g[1], g[2]);
        let f = |v: u8| v as f32 / 255.0;
        let b = is_object(f(t[0]), f(t[1]), f(t[2]));
        intersection += (a && b) as usize;
        union += (a || b) as usize;
    }
    (intersection, union)
}

/// Gaussian negative log-likelihood of `x` under N(m, s²), nats.
fn nll(x: f64, m: f64, s: f64) -> f64 {
    let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
    half_log_2pi + s.ln() + (x - m).powi(2) / (2.0 * s * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_pooled_per_step_and_split_by_role() {
        let mut acc = Accumulator::default();
        acc.begin_sequence();
        let truth_joints = [0.0; JOINTS];
        let truth_frame = [255u8, 255, 0, 0, 0, 0]; // 2 pixels: yellow, black
        let guess_joints = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, -0.05];
        let guess_frame = [1.0, 1.0, 0.0, 0.5, 0.0, 0.0];
        let guess = Guess {
            frame: &guess_frame,
            joints: &guess_joints,
            sigma: None,
        };
        acc.add(guess, &truth_frame, &truth_joints, false, true);
        let exact = Guess {
            frame: &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            joints: &[0.0; JOINTS],
            sigma: None,
        };
        acc.add(exact, &truth_frame, &truth_joints, true, false);
        let q = acc.finish();
        assert_eq!((q.sequences, q.steps), (1, 1));
        assert!((q.joint_rmse - 0.1).abs() < 1e-6, "{q:?}");
        assert!((q.gripper_mae - 0.05).abs() < 1e-6);
        assert!((q.image_mse - 0.25 / 6.0).abs() < 1e-9);
        assert_eq!(q.observed_joint_rmse, 0.0);
        assert_eq!(q.observed_image_mse, 0.0);
        assert_eq!(q.object_iou, Some(1.0));
        assert_eq!(q.image_nll, None);
    }

    #[test]
    fn a_missing_object_scores_zero_overlap() {
        let mut acc = Accumulator::default();
        let grey = [0.55, 0.59, 0.61];
        let guess = Guess {
            frame: &grey,
            joints: &[0.0; JOINTS],
            sigma: Some((&[0.1; 3], &[1.0; JOINTS], &[2.0; JOINTS])),
        };
        acc.add(guess, &[250, 220, 5], &[0.0; JOINTS], false, true);
        let q = acc.finish();
        assert_eq!(q.object_iou, Some(0.0));
        let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert!((q.joint_nll.unwrap() - (half_log_2pi + 0.5f64.ln())).abs() < 1e-9);
        assert!(q.image_nll.unwrap() > 0.0);
        assert_eq!(q.observed_object_iou, None);
    }
}
