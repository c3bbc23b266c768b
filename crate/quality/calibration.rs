use serde::{Deserialize, Serialize};

use super::Scenario;
use crate::data::Sequence;
use crate::model::ModelError;
use crate::predict::{Observations, Predictor};

/// Central coverage levels of the calibration curve: a calibrated Gaussian puts this fraction
/// of the truth within mean ± z·σ, z = [`LEVEL_Z`].
pub const LEVELS: [f64; 10] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95];

/// z = Φ⁻¹((1 + p) / 2) for each of [`LEVELS`].
const LEVEL_Z: [f64; 10] = [
    0.125_661, 0.253_347, 0.385_320, 0.524_401, 0.674_490, 0.841_621, 1.036_433, 1.281_552,
    1.644_854, 1.959_964,
];

/// A true pixel differs from the nearest observation's by more than this (any channel, in
/// [0, 1]) where something moved: the arm and the object, above JPEG noise.
pub const MOVING: f32 = 0.05;

/// How often the truth falls within mean ± z·σ, summed over values (joints, or pixel channels),
/// with the mean σ and the squared error for their ratio.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Coverage {
    values: u64,
    one_sigma: u64,
    two_sigma: u64,
    levels: [u64; 10],
    sigma: f64,
    squared_error: f64,
}

impl Coverage {
    /// Counts one value: `error` = truth − mean and its predicted `sigma`, in the same units.
    pub fn add(&mut self, error: f64, sigma: f64) {
        let z = error.abs() / sigma;
        self.values += 1;
        self.one_sigma += (z <= 1.0) as u64;
        self.two_sigma += (z <= 2.0) as u64;
        for (count, &level) in self.levels.iter_mut().zip(&LEVEL_Z) {
            *count += (z <= level) as u64;
        }
        self.sigma += sigma;
        self.squared_error += error * error;
    }

    /// Adds another coverage's counts.
    pub fn merge(&mut self, other: &Coverage) {
        self.values += other.values;
        self.one_sigma += other.one_sigma;
        self.two_sigma += other.two_sigma;
        for (a, b) in self.levels.iter_mut().zip(other.levels) {
            *a += b;
        }
        self.sigma += other.sigma;
        self.squared_error += other.squared_error;
    }

    /// The fractions and the ratio; `None` when nothing was counted.
    pub fn finish(&self) -> Option<CoverageSummary> {
        if self.values == 0 {
            return None;
        }
        let n = self.values as f64;
        Some(CoverageSummary {
            values: self.values,
            one_sigma: self.one_sigma as f64 / n,
            two_sigma: self.two_sigma as f64 / n,
            sigma_to_rmse: (self.sigma / n) / (self.squared_error / n).sqrt(),
            curve: self.levels.map(|c| c as f64 / n),
        })
    }
}

/// Whether a model's σ tells the truth about its error, over one kind of value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoverageSummary {
    /// Values counted.
    pub values: u64,
    /// Fraction of true values within mean ± σ (calibrated: 0.683).
    pub one_sigma: f64,
    /// Fraction within mean ± 2σ (calibrated: 0.954).
    pub two_sigma: f64,
    /// The mean σ over the RMSE of the same values: 1 for a calibrated constant σ, a little
    /// less for a calibrated σ that varies with the error; well below 1, over-confident.
    pub sigma_to_rmse: f64,
    /// The fraction within each of [`LEVELS`]' central intervals (calibrated: the levels).
    pub curve: [f64; 10],
}

/// A model's calibration at the unobserved scored steps: every joint value (standardised by
/// the joint normalisation, so that joints of different scales weigh alike), every pixel
/// channel, and the channels of pixels that moved since the nearest observation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    pub joints: Option<CoverageSummary>,
    pub pixels: Option<CoverageSummary>,
    pub moving_pixels: Option<CoverageSummary>,
}

/// A calibrated Gaussian's ±2σ coverage.
pub const TWO_SIGMA: f64 = 0.954_5;

/// The joints' errors in units of their predicted σ, |truth − mean| / σ, at the scored steps
/// of a scenario that the predictor did not observe: apart for the steps within the span of
/// the observed times and those outside it, what the two factors of a
/// [`crate::model::JointSigmaScale`] are fitted on.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointZScores {
    pub between: Vec<f64>,
    pub forecast: Vec<f64>,
}

impl JointZScores {
    /// Adds another sequence's scores.
    pub fn extend(&mut self, other: JointZScores) {
        self.between.extend(other.between);
        self.forecast.extend(other.forecast);
    }
}

/// [`JointZScores`] of `predictor` on `seq` in `scenario`; empty when the sequence is too short
/// for the scenario.
pub fn joint_z_scores(
    predictor: &Predictor,
    seq: &Sequence,
    scenario: Scenario,
    observations: usize,
    blend: f32,
) -> Result<JointZScores, ModelError> {
    let mut z = JointZScores::default();
    let Some(steps) = scenario.steps(seq.len(), observations) else {
        return Ok(z);
    };
    let observed = Observations::from_sequence(seq, &steps.observed)?;
    let times = seq.times();
    let prediction = predictor.predict(&observed, &times, blend)?;
    let (first, last) = (
        steps.observed.iter().min().copied().unwrap_or(0),
        steps.observed.iter().max().copied().unwrap_or(0),
    );
    for &k in steps.scored.iter().filter(|k| !steps.observed.contains(k)) {
        let side = if (first..=last).contains(&k) {
            &mut z.between
        } else {
            &mut z.forecast
        };
        let d = seq.joints.width();
        for j in 0..d {
            let i = k * d + j;
            let error = (seq.joints[k][j] - prediction.joint_mean[i]).abs() as f64;
            side.push(error / prediction.joint_sigma[i] as f64);
        }
    }
    Ok(z)
}

/// The factor on σ that makes mean ± 2σ hold [`TWO_SIGMA`] of the values whose standardised
/// errors are `z` (their quantile at that level, halved); `None` without values.
pub fn two_sigma_scale(mut z: Vec<f64>) -> Option<f64> {
    if z.is_empty() {
        return None;
    }
    z.sort_by(f64::total_cmp);
    let at = ((z.len() as f64 * TWO_SIGMA).ceil() as usize).clamp(1, z.len()) - 1;
    Some(z[at] / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A calibrated Gaussian covers the levels, ±1σ and ±2σ; σ half the error's scale covers
    /// less, twice more.
    #[test]
    fn a_calibrated_gaussian_covers_its_levels() {
        // Deterministic standard normal quantiles: errors at the midpoints of 20,000 equal
        // probability bins, σ = 1.
        let n = 20_000;
        let errors: Vec<f64> = (0..n)
            .map(|i| inverse_normal((i as f64 + 0.5) / n as f64))
            .collect();
        let cover = |scale: f64| {
            let mut c = Coverage::default();
            errors.iter().for_each(|&e| c.add(e, scale));
            c.finish().unwrap()
        };
        let calibrated = cover(1.0);
        assert!(
            (calibrated.one_sigma - 0.6827).abs() < 1e-3,
            "{calibrated:?}"
        );
        assert!((calibrated.two_sigma - 0.9545).abs() < 1e-3);
        for (got, want) in calibrated.curve.iter().zip(LEVELS) {
            assert!((got - want).abs() < 1e-3, "{got} {want}");
        }
        assert!((calibrated.sigma_to_rmse - 1.0).abs() < 1e-2);
        let (narrow, wide) = (cover(0.5), cover(2.0));
        assert!((narrow.two_sigma - 0.6827).abs() < 1e-3, "{narrow:?}");
        assert!((wide.one_sigma - 0.9545).abs() < 1e-3, "{wide:?}");
        assert!((narrow.sigma_to_rmse - 0.5).abs() < 1e-2);
        let mut merged = Coverage::default();
        errors.iter().take(10).for_each(|&e| merged.add(e, 1.0));
        let mut rest = Coverage::default();
        errors.iter().skip(10).for_each(|&e| rest.add(e, 1.0));
        merged.merge(&rest);
        let merged = merged.finish().unwrap();
        assert_eq!(
            (merged.values, merged.two_sigma, merged.curve),
            (calibrated.values, calibrated.two_sigma, calibrated.curve)
        );
        assert!((merged.sigma_to_rmse - calibrated.sigma_to_rmse).abs() < 1e-12);
        assert_eq!(Coverage::default().finish(), None);
    }

    /// Errors drawn with σ = 1.5 and predicted with σ = 1: the scale is 1.5; coverage at ±2σ
    /// after scaling is the calibrated one.
    #[test]
    fn the_two_sigma_scale_calibrates_the_band() {
        let n = 20_000;
        let z: Vec<f64> = (0..n)
            .map(|i| 1.5 * inverse_normal((i as f64 + 0.5) / n as f64).abs())
            .collect();
        let scale = two_sigma_scale(z.clone()).unwrap();
        assert!((scale - 1.5).abs() < 0.01, "{scale}");
        let covered = z.iter().filter(|&&v| v <= 2.0 * scale).count() as f64 / n as f64;
        assert!((covered - TWO_SIGMA).abs() < 1e-3, "{covered}");
        assert_eq!(two_sigma_scale(Vec::new()), None);
    }

    /// Φ⁻¹ by bisection on erf (the test's own, independent of `LEVEL_Z`).
    fn inverse_normal(p: f64) -> f64 {
        let cdf = |x: f64| 0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2));
        let (mut lo, mut hi) = (-10.0, 10.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if cdf(mid) < p {
                lo = mid
            } else {
                hi = mid
            }
        }
        0.5 * (lo + hi)
    }

    /// erf, Abramowitz and Stegun 7.1.26 (error < 1.5e-7).
    fn erf(x: f64) -> f64 {
        let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
        let y = 1.0
            - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736)
                * t
                + 0.254_829_592)
                * t
                * (-x * x).exp();
        y.copysign(x)
    }
}
