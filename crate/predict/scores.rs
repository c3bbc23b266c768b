use serde::Serialize;

use super::SequencePrediction;
use crate::data::{Normalization, JOINTS};

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
        joints: &[[f32; JOINTS]],
        normalization: &Normalization,
    ) -> Option<Scores> {
        if frames.len() != prediction.image_mean.len() || joints.len() != prediction.len() {
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
                .iter()
                .flatten()
                .zip(&prediction.joint_mean)
                .zip(&prediction.joint_sigma)
                .enumerate()
                .map(|(i, ((&x, &m), &s))| {
                    let std = normalization.std[i % JOINTS] as f64;
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

    #[test]
    fn perfect_mean_scores_zero_error() {
        let prediction = SequencePrediction {
            image_size: 1,
            times: vec![0.0],
            image_mean: vec![1.0, 0.0, 0.0],
            image_sigma: vec![1.0; 3],
            joint_mean: vec![2.0; 7],
            joint_sigma: vec![2.0; 7],
        };
        let norm = Normalization {
            mean: [0.0; 7],
            std: [2.0; 7],
        };
        let s = Scores::of(&prediction, &[255, 0, 0], &[[2.0; 7]], &norm).unwrap();
        let half_log_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        assert_eq!(s.image_mse, 0.0);
        assert!((s.image_nll - half_log_2pi).abs() < 1e-12);
        assert!(
            (s.joint_nll - half_log_2pi).abs() < 1e-12,
            "σ 2 / std 2 = 1"
        );
        assert!(Scores::of(&prediction, &[0; 6], &[[2.0; 7]], &norm).is_none());
    }
}
