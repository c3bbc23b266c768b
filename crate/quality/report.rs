use serde::Serialize;

use super::accumulator::{Guess, Sigma};
use super::{Accumulator, CoverageSummary, MeanMotion, Quality, Scenario};
use crate::data::Sequence;
use crate::futures::{FutureScoreRow, Sampling};
use crate::model::{linear_weights, ModelError};
use crate::predict::{Observations, Predictor};

/// One sequence's sums for the model and the baselines.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SequenceScores {
    /// The model's prediction.
    pub model: Accumulator,
    /// Linear joints and the nearest observed frame (hold-last past the last observation).
    pub baseline: Accumulator,
    /// The action's mean motion, when one was given.
    pub mean_motion: Option<Accumulator>,
}

/// Scores `predictor` on `seq` (of `action`) in `scenario`: observes the scenario's steps with
/// blending coefficient `blend`, predicts every step and compares the model, the trivial
/// baseline and (with `mean`) the action's mean motion on the scored and the observed steps.
/// `Ok(None)` when the sequence is too short for the scenario.
pub fn score_sequence(
    predictor: &Predictor,
    seq: &Sequence,
    action: &str,
    scenario: Scenario,
    observations: usize,
    blend: f32,
    mean: Option<&MeanMotion>,
) -> Result<Option<SequenceScores>, ModelError> {
    let Some(steps) = scenario.steps(seq.len(), observations) else {
        return Ok(None);
    };
    let times = seq.times();
    let observed = Observations::from_sequence(seq, &steps.observed)?;
    let prediction = predictor.predict(&observed, &times, blend)?;
    let std = predictor.normalization().std.clone();
    let n = seq.frame_bytes();
    let mut scores = SequenceScores {
        mean_motion: mean.map(|_| Accumulator::default()),
        ..Default::default()
    };
    scores.model.begin_sequence();
    scores.baseline.begin_sequence();
    if let Some(acc) = scores.mean_motion.as_mut() {
        acc.begin_sequence();
    }
    let observed_frames: Vec<Vec<f32>> = steps
        .observed
        .iter()
        .map(|&k| seq.frame(k).iter().map(|&v| v as f32 / 255.0).collect())
        .collect();
    for (k, &time) in times.iter().enumerate() {
        let is_observed = steps.observed.contains(&k);
        let is_scored = steps.scored.binary_search(&k).is_ok();
        if !is_observed && !is_scored {
            continue;
        }
        let (frame, joints) = (seq.frame(k), &seq.joints[k]);
        let (nearest, baseline_joints) = baseline(seq, &steps.observed, k);
        let model = Guess {
            frame: &prediction.image_mean[k * n..(k + 1) * n],
            joints: prediction.joint_mean_at(k),
            sigma: Some(Sigma {
                frame: prediction.sigma_frame(k),
                joints: prediction.joint_sigma_at(k),
                std: &std,
                nearest: &observed_frames[nearest],
            }),
        };
        scores
            .model
            .add(model, frame, joints, is_observed, is_scored);
        let baseline = Guess {
            frame: &observed_frames[nearest],
            joints: &baseline_joints,
            sigma: None,
        };
        scores
            .baseline
            .add(baseline, frame, joints, is_observed, is_scored);
        if let (Some(mean), Some(acc)) = (mean, scores.mean_motion.as_mut()) {
            let Some((mean_frame, mean_joints)) = mean.at(action, time) else {
                return Err(ModelError::observation(
                    "action",
                    format!(
                        "{action:?} has no mean motion: the reference set holds no such action"
                    ),
                ));
            };
            let guess = Guess {
                frame: mean_frame,
                joints: &mean_joints,
                sigma: None,
            };
            acc.add(guess, frame, joints, is_observed, is_scored);
        }
    }
    Ok(Some(scores))
}

/// The trivial baseline at step `k`: the index (into `observed`) of the nearest observation,
/// for its frame, and the joints linearly interpolated between the observations around `k`
/// (held before the first and after the last).
fn baseline(seq: &Sequence, observed: &[usize], k: usize) -> (usize, Vec<f32>) {
    let nearest = (0..observed.len())
        .min_by_key(|&i| observed[i].abs_diff(k))
        .unwrap_or(0);
    // Step indices are times too: the phase is linear in them.
    let steps: Vec<f32> = observed.iter().map(|&o| o as f32).collect();
    let weights = linear_weights(&steps, &vec![true; steps.len()], k as f32);
    let joints = (0..seq.joints.width())
        .map(|j| {
            observed
                .iter()
                .zip(&weights)
                .map(|(&o, w)| w * seq.joints[o][j])
                .sum()
        })
        .collect();
    (nearest, joints)
}

/// One number of a coverage summary, for the calibration table.
type Measure = fn(&CoverageSummary) -> f64;

/// One row of the benchmark's table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QualityRow {
    /// A model file's name, or a baseline's.
    pub name: String,
    /// Whether the row is a trained model (`false`: a baseline).
    pub model: bool,
    pub quality: Quality,
}

/// The benchmark for one scenario: every model's row and the baselines'.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QualityReport {
    pub scenario: Scenario,
    /// Observations per sequence (K for `interp`, 3 for `extrap`).
    pub observations: usize,
    /// Blending coefficient the models were run with.
    pub blend: f32,
    pub rows: Vec<QualityRow>,
    /// Sampled futures of the unobserved steps, per model (`dmbn score --samples`; none
    /// without).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub futures: Vec<FutureScoreRow>,
    /// How they were sampled.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<Sampling>,
}

impl QualityReport {
    /// The table as Markdown: joint errors in radians, image MSE in pixel units, NLL per value.
    pub fn markdown(&self) -> String {
        let what = match self.scenario {
            Scenario::Interp => format!(
                "{} evenly spaced observations, every step",
                self.observations
            ),
            Scenario::Extrap => "the first 30% observed at 3 steps, the rest".to_string(),
        };
        let mut out = format!(
            "scenario {} ({what}), blend {}\n\n| | sequences | joint RMSE (rad) | gripper MAE | image MSE | joint RMSE observed | image MSE observed | object IoU | object IoU observed | image NLL | joint NLL |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
            self.scenario, self.blend
        );
        let opt = |v: Option<f64>, digits: usize| {
            v.map_or("—".to_string(), |v| format!("{v:.digits$}"))
        };
        for row in &self.rows {
            let q = &row.quality;
            out.push_str(&format!(
                "| {} | {} | {:.4} | {:.4} | {:.5} | {:.4} | {:.5} | {} | {} | {} | {} |\n",
                row.name,
                q.sequences,
                q.joint_rmse,
                q.gripper_mae,
                q.image_mse,
                q.observed_joint_rmse,
                q.observed_image_mse,
                opt(q.object_iou, 3),
                opt(q.observed_object_iou, 3),
                opt(q.image_nll, 3),
                opt(q.joint_nll, 3),
            ));
        }
        out.push_str(&self.futures_markdown());
        let calibrated: Vec<_> = self
            .rows
            .iter()
            .filter_map(|row| Some((&row.name, row.quality.calibration?)))
            .collect();
        if calibrated.is_empty() {
            return out;
        }
        out.push_str(
            "\ncalibration at the unobserved steps (a calibrated Gaussian: ±1σ 68.3%, ±2σ 95.4%, σ / RMSE 1)\n\n| | joints ±1σ | joints ±2σ | joints σ / RMSE | pixels ±1σ | pixels ±2σ | pixels σ / RMSE | moving pixels ±2σ | moving pixels σ / RMSE |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        let cell =
            |c: Option<CoverageSummary>, what: fn(&CoverageSummary) -> f64, percent: bool| {
                c.map_or("—".to_string(), |c| {
                    if percent {
                        format!("{:.1}%", 100.0 * what(&c))
                    } else {
                        format!("{:.2}", what(&c))
                    }
                })
            };
        let one: Measure = |c| c.one_sigma;
        let two: Measure = |c| c.two_sigma;
        let ratio: Measure = |c| c.sigma_to_rmse;
        for (name, c) in calibrated {
            out.push_str(&format!(
                "| {name} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                cell(c.joints, one, true),
                cell(c.joints, two, true),
                cell(c.joints, ratio, false),
                cell(c.pixels, one, true),
                cell(c.pixels, two, true),
                cell(c.pixels, ratio, false),
                cell(c.moving_pixels, two, true),
                cell(c.moving_pixels, ratio, false),
            ));
        }
        out
    }
}

impl QualityReport {
    /// The sampled futures' table (empty without them).
    fn futures_markdown(&self) -> String {
        let Some(s) = &self.sampling else {
            return String::new();
        };
        let mut out = format!(
            "\n{} sampled futures of the unobserved steps ({}): arm joints, rad, mean over the sequences (energy score: lower is better; the single mean's is its RMSE)\n\n| | sequences | energy score | single mean's | best of {} | a future's RMSE |\n|---|---:|---:|---:|---:|---:|\n",
            s.samples,
            s.describe(),
            s.samples
        );
        for row in &self.futures {
            let f = &row.scores;
            out.push_str(&format!(
                "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} |\n",
                row.name, row.sequences, f.energy, f.energy_of_mean, f.best_rmse, f.sample_rmse
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;

    #[test]
    fn the_baseline_interpolates_and_holds() {
        let seq = Sequence {
            image_size: 1,
            joints: (0..7).map(|k| [k as f32; JOINTS]).collect(),
            endpoint: Some(vec![[0.0; 7]; 7]),
            object: Some(vec![[0.0; 3]; 7]),
            frames: vec![0; 21],
        };
        let observed = [1, 3];
        assert_eq!(baseline(&seq, &observed, 0), (0, vec![1.0; JOINTS]));
        assert_eq!(baseline(&seq, &observed, 2), (0, vec![2.0; JOINTS]));
        assert_eq!(baseline(&seq, &observed, 3), (1, vec![3.0; JOINTS]));
        assert_eq!(baseline(&seq, &observed, 6), (1, vec![3.0; JOINTS]));
    }
}
