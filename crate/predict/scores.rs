use serde::Serialize;

use super::SequencePrediction;
use crate::data::{Joints, Normalization};

/// How well a prediction matches the true sequence, averaged over every target step: the
/// reconstruction error and Gaussian negative log-likelihood per value (nats) of each
/// modality. Pixels are in [0, 1]; joints in normalised units (as in training), so the
/// numbers compare across joints and with the training metrics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scores {
    pub image_mse: f64,
    pub image_nll: f64,
    pub joint_mse: f64,
    pub joint_nll: f64,
}

impl Scores {
    /// Scores `prediction` against true `frames` (RGB bytes, one frame per target) and
    /// `joints` (one row per target, dataset units), with the model's `normalization`.
    /// Returns `None` when the lengths do not match the prediction.
    pub fn of(
        prediction: &SequencePrediction,
        frames: &[u8],
        joints: &Joints,
        normalization: &Normalization,
    ) -> Option<Scores> {
        let d = normalization.width();
        if frames.len() != prediction.image_mean.len()
            || joints.len() != prediction.len()
            || joints.width() != d
        {
            return None;
        }
        let (image_mse, image_nll) = gaussian(
            frames
                .iter()
                .zip(&prediction.image_mean)
                .zip(&prediction.image_sigma)
                .map(|((&x, &m), &s)| (x as f64 / 255.0, m as f64, s as f64)),
        );
        let (joint_mse, joint_nll) = gaussian(
            joints
                .values()
                .iter()
                .zip(&prediction.joint_mean)
                .zip(&prediction.joint_sigma)
                .enumerate()
                .map(|(i, ((&x, &m), &s))| {
                    let std = normalization.std[i % d] as f64;
                    (x as f64 / std, m as f64 / std, s as f64 / std)
                }),
        );
        Some(Scores {
            image_mse,
            image_nll,
            joint_mse,
            joint_nll,
        })
    }
}

/// Mean squared error and mean Gaussian NLL of (value, mean, σ) triples.
fn gaussian(values: impl Iterator<Item = (f64, f64, f64)>) -> (f64, f64) {
    let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
    let (mut n, mut se, mut nll) = (0.0, 0.0, 0.0);
    for (x, m, s) in values {
        let d2 = (x - m) * (x - m);
        n += 1.0;
        se += d2;
        nll += half_log_2pi + s.ln() + d2 / (2.0 * s * s);
    }
    let n = f64::max(n, 1.0);
    (se / n, nll / n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;

    #[test]
    fn perfect_mean_scores_zero_error() {
        let prediction = SequencePrediction {
            image_size: 1,
            joints: JOINTS,
            times: vec![0.0],
            image_mean: vec![1.0, 0.0, 0.0],
            image_sigma: vec![1.0; 3],
            joint_mean: vec![2.0; 7],
            joint_sigma: vec![2.0; 7],
        };
        let norm = Normalization {
            mean: vec![0.0; 7],
            std: vec![2.0; 7],
        };
        let s = Scores::of(
            &prediction,
            &[255, 0, 0],
            &Joints::from_rows(&[[2.0; 7]]),
            &norm,
        )
        .unwrap();
        let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert_eq!(s.image_mse, 0.0);
        assert!((s.image_nll - half_log_2pi).abs() < 1e-12);
        assert!(
            (s.joint_nll - half_log_2pi).abs() < 1e-12,
            "σ 2 / std 2 = 1"
        );
        assert!(Scores::of(&prediction, &[0; 6], &Joints::from_rows(&[[2.0; 7]]), &norm).is_none());
    }

    /// Gaussian NLL of one value `d` away from the mean, σ `s`: the definition.
    fn nll(d: f64, s: f64) -> f64 {
        0.5 * (2.0 * std::f64::consts::PI).ln() + s.ln() + d * d / (2.0 * s * s)
    }

    fn mean(v: impl Iterator<Item = f64>) -> f64 {
        let v: Vec<f64> = v.collect();
        v.iter().sum::<f64>() / v.len() as f64
    }

    #[test]
    fn errors_are_scored_per_value_pixels_in_unit_range_joints_in_normalised_units() {
        // Two targets of one pixel: bytes scaled to [0, 1] before comparing.
        let frames = [255, 0, 51, 102, 204, 153];
        let image_mean = [0.5f32, 0.25, 0.2, 0.6, 0.4, 0.6];
        let image_sigma = [0.5f32, 1.0, 0.25, 2.0, 0.1, 0.5];
        // Joints: a different std per column (and a mean), and per value the error z and σ r
        // in normalised units; the prediction is in dataset units (x + std·z, σ std·r).
        let norm = Normalization {
            mean: vec![1.0, -2.0, 0.5, 3.0, 0.0, -1.0, 2.0],
            std: vec![0.5, 2.0, 4.0, 0.25, 8.0, 1.0, 0.125],
        };
        let truth = [
            [0.25f32, -1.5, 2.0, 3.5, -4.0, 0.75, 2.5],
            [1.0, 0.5, -3.0, 2.75, 6.0, -0.5, 1.875],
        ];
        let z = [
            [0.5, -1.0, 0.25, 2.0, 0.0, -0.5, 1.0],
            [1.0, 0.5, -2.0, 0.25, 1.5, -1.0, 0.0],
        ];
        let r = [
            [1.0, 0.5, 2.0, 1.0, 0.25, 1.0, 0.5],
            [2.0, 1.0, 0.5, 4.0, 1.0, 0.5, 1.0],
        ];
        let mut joint_mean = Vec::new();
        let mut joint_sigma = Vec::new();
        for k in 0..2 {
            for j in 0..JOINTS {
                let std = norm.std[j];
                joint_mean.push(truth[k][j] + std * z[k][j] as f32);
                joint_sigma.push(std * r[k][j] as f32);
            }
        }
        let prediction = SequencePrediction {
            image_size: 1,
            joints: JOINTS,
            times: vec![0.0, 1.0],
            image_mean: image_mean.to_vec(),
            image_sigma: image_sigma.to_vec(),
            joint_mean,
            joint_sigma,
        };
        let s = Scores::of(&prediction, &frames, &Joints::from_rows(&truth), &norm).unwrap();

        let pixels = || {
            (0..6).map(|i| {
                let d = frames[i] as f64 / 255.0 - image_mean[i] as f64;
                (d, image_sigma[i] as f64)
            })
        };
        let joints = || (0..14).map(|i| (z[i / 7][i % 7], r[i / 7][i % 7]));
        let expected = Scores {
            image_mse: mean(pixels().map(|(d, _)| d * d)),
            image_nll: mean(pixels().map(|(d, s)| nll(d, s))),
            joint_mse: mean(joints().map(|(z, _)| z * z)),
            joint_nll: mean(joints().map(|(z, r)| nll(z, r))),
        };
        // By hand: the pixel errors are 0.5, -0.25, 0, -0.2, 0.4, 0; the joint z² sum to 15.125.
        assert!(
            (expected.image_mse - 0.5125 / 6.0).abs() < 1e-9,
            "{expected:?}"
        );
        assert!(
            (expected.joint_mse - 15.125 / 14.0).abs() < 1e-12,
            "{expected:?}"
        );
        for (name, got, want) in [
            ("image MSE", s.image_mse, expected.image_mse),
            ("image NLL", s.image_nll, expected.image_nll),
            ("joint MSE", s.joint_mse, expected.joint_mse),
            ("joint NLL", s.joint_nll, expected.joint_nll),
        ] {
            assert!(
                (got - want).abs() < 1e-6 * want.abs().max(1.0),
                "{name}: {got}, expected {want} ({s:?})"
            );
        }
    }
}
