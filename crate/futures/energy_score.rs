use serde::Serialize;

use crate::data::{arm_joints, Joints};

/// Scores of a set of sampled trajectories against the truth, in the units of the values
/// (radians for arm joints). Every norm is an RMS, ‖x‖ = √(Σ xᵢ² / n), so that a single
/// trajectory's score is its RMSE.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyScore;

impl EnergyScore {
    /// The energy score ES = (1/S) Σₛ ‖Xₛ − y‖ − 1/(2S²) Σₛ Σₛ' ‖Xₛ − Xₛ'‖ of the samples `xs`
    /// (each as long as `truth`) against `truth` (Gneiting & Raftery 2007): strictly proper,
    /// lower is better. The first term rewards samples near the truth, the second their
    /// spread; S identical samples (a single mean) score their RMSE.
    pub fn of(xs: &[Vec<f32>], truth: &[f32]) -> f64 {
        let s = xs.len();
        if s == 0 {
            return f64::NAN;
        }
        let near = xs.iter().map(|x| rms(x, truth)).sum::<f64>() / s as f64;
        let mut spread = 0.0;
        for (i, a) in xs.iter().enumerate() {
            for b in &xs[i + 1..] {
                spread += 2.0 * rms(a, b);
            }
        }
        near - spread / (2.0 * (s * s) as f64)
    }

    /// The best sample's RMSE (minADE-style): rewards spraying, so it is reported, not judged.
    pub fn best_rmse(xs: &[Vec<f32>], truth: &[f32]) -> f64 {
        xs.iter().map(|x| rms(x, truth)).fold(f64::NAN, f64::min)
    }
}

/// Sampled futures against the truth over the imagined steps, arm joints only (all values a
/// step but the last, the gripper: as the quality benchmark's joint RMSE), in radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FutureScores {
    /// The samples' energy score ([`EnergyScore::of`]).
    pub energy: f64,
    /// The single-mean prediction's, taken as S identical samples: its RMSE.
    pub energy_of_mean: f64,
    /// The best sample's RMSE (minADE-style; reported, not judged).
    pub best_rmse: f64,
    /// The samples' mean RMSE.
    pub sample_rmse: f64,
}

impl FutureScores {
    /// `samples` and the single `mean` (each a row per step of the sequence) against `truth`
    /// at the imagined `steps`.
    pub fn of(samples: &[Joints], mean: &Joints, truth: &Joints, steps: &[usize]) -> Self {
        let y = arm_values(truth, steps);
        let xs: Vec<Vec<f32>> = samples.iter().map(|s| arm_values(s, steps)).collect();
        let rmses: Vec<f64> = xs.iter().map(|x| rms(x, &y)).collect();
        FutureScores {
            energy: EnergyScore::of(&xs, &y),
            energy_of_mean: rms(&arm_values(mean, steps), &y),
            best_rmse: EnergyScore::best_rmse(&xs, &y),
            sample_rmse: rmses.iter().sum::<f64>() / rmses.len().max(1) as f64,
        }
    }
}

/// [`FutureScores`] summed over sequences, for a table row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FutureScoreSums {
    sequences: usize,
    sums: [f64; 4],
}

impl FutureScoreSums {
    /// Counts one sequence's scores.
    pub fn add(&mut self, s: &FutureScores) {
        self.sequences += 1;
        let values = [s.energy, s.energy_of_mean, s.best_rmse, s.sample_rmse];
        for (sum, v) in self.sums.iter_mut().zip(values) {
            *sum += v;
        }
    }

    /// The row `name`: every score averaged over the sequences counted.
    pub fn row(&self, name: &str) -> FutureScoreRow {
        let n = self.sequences.max(1) as f64;
        let [energy, energy_of_mean, best_rmse, sample_rmse] = self.sums.map(|s| s / n);
        FutureScoreRow {
            name: name.to_string(),
            sequences: self.sequences,
            scores: FutureScores {
                energy,
                energy_of_mean,
                best_rmse,
                sample_rmse,
            },
        }
    }
}

/// A model's sampled futures scored over a set of sequences (each score's mean).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FutureScoreRow {
    pub name: String,
    pub sequences: usize,
    #[serde(flatten)]
    pub scores: FutureScores,
}

/// The arm joints of `joints` at `steps`, flat.
fn arm_values(joints: &Joints, steps: &[usize]) -> Vec<f32> {
    let arm = arm_joints(joints.width());
    steps
        .iter()
        .flat_map(|&k| joints[k][..arm].to_vec())
        .collect()
}

/// ‖a − b‖ as an RMS over the values.
fn rms(a: &[f32], b: &[f32]) -> f64 {
    let n = a.len().max(1) as f64;
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum();
    (se / n).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_scores_its_rmse_and_spread_around_the_truth_scores_better_than_a_miss() {
        let truth = vec![1.0f32, 1.0];
        let mean = vec![vec![0.0f32, 0.0]; 4];
        assert!((EnergyScore::of(&mean, &truth) - 1.0).abs() < 1e-12);
        // Samples around the truth beat the mean that misses it...
        let spread = vec![
            vec![0.5f32, 0.5],
            vec![1.5, 1.5],
            vec![0.8, 0.8],
            vec![1.2, 1.2],
        ];
        assert!(EnergyScore::of(&spread, &truth) < EnergyScore::of(&mean, &truth));
        // ...and samples sprayed far from it do worse than samples at it.
        let at = vec![vec![1.0f32, 1.0]; 4];
        let far = vec![
            vec![-5.0f32, -5.0],
            vec![7.0, 7.0],
            vec![-5.0, -5.0],
            vec![7.0, 7.0],
        ];
        assert!(EnergyScore::of(&at, &truth) < EnergyScore::of(&far, &truth));
        assert_eq!(EnergyScore::best_rmse(&spread, &truth), 0.19999998807907104);
    }

    #[test]
    fn the_score_is_proper_on_a_known_distribution() {
        // Truth from N(0, 1) per value: samples from N(0, 1) score better on average than
        // samples from N(0, 0.3²) or N(1, 1).
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        let mut normal = |scale: f32, shift: f32| -> Vec<f32> {
            (0..6)
                .map(|_| {
                    let (u1, u2) = (
                        1.0 - rng.random_range(0.0f64..1.0),
                        rng.random_range(0.0f64..1.0),
                    );
                    let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    shift + scale * z as f32
                })
                .collect()
        };
        let (mut right, mut narrow, mut shifted) = (0.0, 0.0, 0.0);
        for _ in 0..400 {
            let truth = normal(1.0, 0.0);
            let draws = |scale, shift, normal: &mut dyn FnMut(f32, f32) -> Vec<f32>| {
                (0..8).map(|_| normal(scale, shift)).collect::<Vec<_>>()
            };
            right += EnergyScore::of(&draws(1.0, 0.0, &mut normal), &truth);
            narrow += EnergyScore::of(&draws(0.3, 0.0, &mut normal), &truth);
            shifted += EnergyScore::of(&draws(1.0, 1.0, &mut normal), &truth);
        }
        assert!(right < narrow, "{right} vs {narrow}");
        assert!(right < shifted, "{right} vs {shifted}");
    }
}
