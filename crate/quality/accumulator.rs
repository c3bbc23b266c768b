use serde::{Deserialize, Serialize};

use super::calibration::{Calibration, Coverage, MOVING};
use super::is_object;
use crate::data::arm_joints;

/// Sums of errors over the steps of one or more sequences, pooled so that every step weighs
/// the same; [`Accumulator::finish`] turns them into a [`Quality`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Accumulator {
    sequences: usize,
    steps: usize,
    joint_se: f64,
    joint_values: usize,
    grippers: usize,
    gripper_ae: f64,
    image_se: f64,
    image_values: usize,
    observed_steps: usize,
    observed_joint_se: f64,
    observed_joint_values: usize,
    observed_image_se: f64,
    observed_image_values: usize,
    image_nll: f64,
    joint_nll: f64,
    nll_steps: usize,
    object_intersection: usize,
    object_union: usize,
    observed_object_intersection: usize,
    observed_object_union: usize,
    joint_coverage: Coverage,
    pixel_coverage: Coverage,
    moving_coverage: Coverage,
}

/// One guess at one step: the mean frame (interleaved RGB in [0, 1]) and joints (dataset
/// units), with σ when the guess is a model's prediction.
#[derive(Debug, Clone, Copy)]
pub struct Guess<'a> {
    pub frame: &'a [f32],
    pub joints: &'a [f32],
    pub sigma: Option<Sigma<'a>>,
}

/// A prediction's σ at one step, and what its NLL and calibration are measured against.
#[derive(Debug, Clone, Copy)]
pub struct Sigma<'a> {
    /// σ of every pixel channel.
    pub frame: &'a [f32],
    /// σ of every joint (dataset units).
    pub joints: &'a [f32],
    /// The joints' standard deviations: NLL and joint coverage are per value in normalised
    /// joint units, as in training.
    pub std: &'a [f32],
    /// The nearest observation's frame (RGB in [0, 1]): pixels that differ from it moved.
    pub nearest: &'a [f32],
}

/// The benchmark's measures of one model or baseline over a set of sequences.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// Sequences scored.
    pub sequences: usize,
    /// Scored steps over all sequences.
    pub steps: usize,
    /// Root mean squared error of the arm joints (all joint values but the gripper, the
    /// last) over the scored steps, radians.
    pub joint_rmse: f64,
    /// Mean absolute error of the gripper value over the scored steps (dataset units; NaN
    /// for a robot of one joint value, which has none).
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
    /// How well σ describes the error at the scored steps that were not observed (models
    /// only).
    #[serde(default)]
    pub calibration: Option<Calibration>,
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
        joints: &[f32],
        observed: bool,
        scored: bool,
    ) {
        let d = joints.len();
        let arm = arm_joints(d);
        let joint_se: f64 = (0..arm)
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
            self.observed_joint_values += arm;
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
        self.joint_values += arm;
        if arm < d {
            self.grippers += 1;
            self.gripper_ae += (guess.joints[arm] as f64 - joints[arm] as f64).abs();
        }
        self.image_se += image_se;
        self.image_values += frame.len();
        self.object_intersection += intersection;
        self.object_union += union;
        if let Some(sigma) = guess.sigma {
            if !observed {
                self.cover(guess, sigma, frame, joints);
            }
            let (image_sigma, joint_sigma, std) = (sigma.frame, sigma.joints, sigma.std);
            self.nll_steps += 1;
            self.image_nll += frame
                .iter()
                .zip(guess.frame)
                .zip(image_sigma)
                .map(|((&x, &m), &s)| nll(x as f64 / 255.0, m as f64, s as f64))
                .sum::<f64>()
                / frame.len() as f64;
            self.joint_nll += (0..d)
                .map(|j| {
                    let std = std[j] as f64;
                    nll(
                        joints[j] as f64 / std,
                        guess.joints[j] as f64 / std,
                        joint_sigma[j] as f64 / std,
                    )
                })
                .sum::<f64>()
                / d as f64;
        }
    }

    /// Counts how often the truth lies within the guess's σ bands.
    fn cover(&mut self, guess: Guess, sigma: Sigma, frame: &[u8], joints: &[f32]) {
        for (j, truth) in joints.iter().enumerate() {
            let std = sigma.std[j] as f64;
            let error = (truth - guess.joints[j]) as f64 / std;
            self.joint_coverage.add(error, sigma.joints[j] as f64 / std);
        }
        for ((truth, mean), (s, near)) in
            frame.chunks_exact(3).zip(guess.frame.chunks_exact(3)).zip(
                sigma
                    .frame
                    .chunks_exact(3)
                    .zip(sigma.nearest.chunks_exact(3)),
            )
        {
            let truth: [f32; 3] = std::array::from_fn(|c| truth[c] as f32 / 255.0);
            let moved = (0..3).any(|c| (truth[c] - near[c]).abs() > MOVING);
            for c in 0..3 {
                let (error, sigma) = ((truth[c] - mean[c]) as f64, s[c] as f64);
                self.pixel_coverage.add(error, sigma);
                if moved {
                    self.moving_coverage.add(error, sigma);
                }
            }
        }
    }

    /// Adds another accumulator's sums (another set of sequences).
    pub fn merge(&mut self, other: &Accumulator) {
        self.sequences += other.sequences;
        self.steps += other.steps;
        self.joint_se += other.joint_se;
        self.joint_values += other.joint_values;
        self.grippers += other.grippers;
        self.gripper_ae += other.gripper_ae;
        self.image_se += other.image_se;
        self.image_values += other.image_values;
        self.observed_steps += other.observed_steps;
        self.observed_joint_se += other.observed_joint_se;
        self.observed_joint_values += other.observed_joint_values;
        self.observed_image_se += other.observed_image_se;
        self.observed_image_values += other.observed_image_values;
        self.image_nll += other.image_nll;
        self.joint_nll += other.joint_nll;
        self.nll_steps += other.nll_steps;
        self.object_intersection += other.object_intersection;
        self.object_union += other.object_union;
        self.observed_object_intersection += other.observed_object_intersection;
        self.observed_object_union += other.observed_object_union;
        self.joint_coverage.merge(&other.joint_coverage);
        self.pixel_coverage.merge(&other.pixel_coverage);
        self.moving_coverage.merge(&other.moving_coverage);
    }

    /// The measures; NaN where nothing was counted.
    pub fn finish(&self) -> Quality {
        let div = |a: f64, n: usize| if n == 0 { f64::NAN } else { a / n as f64 };
        let iou = |i: usize, u: usize| (u > 0).then(|| i as f64 / u as f64);
        Quality {
            sequences: self.sequences,
            steps: self.steps,
            joint_rmse: div(self.joint_se, self.joint_values).sqrt(),
            gripper_mae: div(self.gripper_ae, self.grippers),
            image_mse: div(self.image_se, self.image_values),
            observed_joint_rmse: div(self.observed_joint_se, self.observed_joint_values).sqrt(),
            observed_image_mse: div(self.observed_image_se, self.observed_image_values),
            image_nll: (self.nll_steps > 0).then(|| self.image_nll / self.nll_steps as f64),
            joint_nll: (self.nll_steps > 0).then(|| self.joint_nll / self.nll_steps as f64),
            object_iou: iou(self.object_intersection, self.object_union),
            observed_object_iou: iou(
                self.observed_object_intersection,
                self.observed_object_union,
            ),
            calibration: (self.nll_steps > 0).then(|| Calibration {
                joints: self.joint_coverage.finish(),
                pixels: self.pixel_coverage.finish(),
                moving_pixels: self.moving_coverage.finish(),
            }),
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
    use crate::data::JOINTS;

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

    /// A prediction whose errors are Gaussian with its own σ covers ±1σ and ±2σ as a
    /// Gaussian does, for joints (whatever their scale) and pixels; pixels that did not move
    /// since the nearest observation are left out of the moving ones; observed steps count
    /// for nothing.
    #[test]
    fn errors_of_the_predicted_sigma_cover_as_a_gaussian() {
        // Standard normal quantiles at 400 equal-probability midpoints: bisection on Φ,
        // integrated by Simpson's rule.
        let quantile = |p: f64| {
            let (mut lo, mut hi) = (-8.0f64, 8.0f64);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                let n = 200;
                let h = mid / n as f64;
                let f = |x: f64| (-x * x / 2.0).exp() / (2.0 * std::f64::consts::PI).sqrt();
                let integral: f64 = (0..n)
                    .map(|i| {
                        let a = i as f64 * h;
                        h / 6.0 * (f(a) + 4.0 * f(a + h / 2.0) + f(a + h))
                    })
                    .sum();
                if 0.5 + integral < p {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            0.5 * (lo + hi)
        };
        let steps = 400;
        let z: Vec<f32> = (0..steps)
            .map(|i| quantile((i as f64 + 0.5) / steps as f64) as f32)
            .collect();
        let std = [0.5, 1.0, 2.0, 0.1, 3.0, 1.0, 0.02];
        let joint_sigma: [f32; JOINTS] = std::array::from_fn(|j| 0.3 * std[j]);
        let mut acc = Accumulator::default();
        acc.begin_sequence();
        // Two pixels: the first moved since the nearest observation (black), the second not.
        let truth_frame = [200u8, 100, 50, 10, 20, 30];
        let nearest = [0.0, 0.0, 0.0, 10.0 / 255.0, 20.0 / 255.0, 30.0 / 255.0];
        let pixel_sigma = [0.05f32; 6];
        for (k, &zk) in z.iter().enumerate() {
            let joints: [f32; JOINTS] = std::array::from_fn(|j| j as f32 - zk * joint_sigma[j]);
            // Every pixel channel errs by the same z; the second pixel doubly (σ says 0.05).
            let frame: Vec<f32> = truth_frame
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    v as f32 / 255.0 - zk * pixel_sigma[i] * if i < 3 { 1.0 } else { 2.0 }
                })
                .collect();
            let guess = Guess {
                frame: &frame,
                joints: &joints,
                sigma: Some(Sigma {
                    frame: &pixel_sigma,
                    joints: &joint_sigma,
                    std: &std,
                    nearest: &nearest,
                }),
            };
            let truth: [f32; JOINTS] = std::array::from_fn(|j| j as f32);
            acc.add(guess, &truth_frame, &truth, false, true);
            // An observed step with a wild guess: not counted.
            if k % 10 == 0 {
                let wild = Guess {
                    joints: &[100.0; JOINTS],
                    ..guess
                };
                acc.add(wild, &truth_frame, &truth, true, true);
            }
        }
        let c = acc.finish().calibration.unwrap();
        let (joints, pixels, moving) = (
            c.joints.unwrap(),
            c.pixels.unwrap(),
            c.moving_pixels.unwrap(),
        );
        assert_eq!(joints.values, (steps * JOINTS) as u64);
        assert!((joints.one_sigma - 0.6827).abs() < 0.005, "{joints:?}");
        assert!((joints.two_sigma - 0.9545).abs() < 0.005, "{joints:?}");
        assert!((joints.sigma_to_rmse - 1.0).abs() < 0.01, "{joints:?}");
        // The moving pixel is calibrated; the still one errs twice its σ.
        assert_eq!(moving.values, (steps * 3) as u64);
        assert!((moving.two_sigma - 0.9545).abs() < 0.005, "{moving:?}");
        assert_eq!(pixels.values, (steps * 6) as u64);
        assert!(
            (pixels.two_sigma - (0.9545 + 0.6827) / 2.0).abs() < 0.005,
            "{pixels:?}"
        );
    }

    #[test]
    fn a_missing_object_scores_zero_overlap() {
        let mut acc = Accumulator::default();
        let grey = [0.55, 0.59, 0.61];
        let guess = Guess {
            frame: &grey,
            joints: &[0.0; JOINTS],
            sigma: Some(Sigma {
                frame: &[0.1; 3],
                joints: &[1.0; JOINTS],
                std: &[2.0; JOINTS],
                nearest: &grey,
            }),
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
