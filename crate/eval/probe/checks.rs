//! When the probe's numbers are to be doubted: diverged heads and splits too small.

/// A head counts as diverged when its test MSE is above this many times Var(t) of the test
/// steps (what predicting the mean time scores), or is not finite.
pub const DIVERGENCE_FACTOR: f64 = 2.0;
/// Fewer test ids than this make the probe's numbers anecdotal: a warning.
pub const MIN_TEST_IDS: usize = 3;
/// Fewer test steps than this: a warning.
pub const MIN_TEST_STEPS: usize = 100;
/// Fewer training ids than this: a warning (the heads can memorise them).
pub const MIN_TRAIN_IDS: usize = 5;

/// True when a head of test MSE `mse` has diverged (or overfit): not finite, or above
/// [`DIVERGENCE_FACTOR`] × `var_t`, `var_t` being the variance of the test times.
pub fn diverged(mse: f64, var_t: f64) -> bool {
    !mse.is_finite() || mse > DIVERGENCE_FACTOR * var_t
}

/// Population variance of `times` (NaN for none).
pub fn time_variance(times: &[f32]) -> f64 {
    if times.is_empty() {
        return f64::NAN;
    }
    let n = times.len() as f64;
    let mean = times.iter().map(|&t| t as f64).sum::<f64>() / n;
    times
        .iter()
        .map(|&t| (t as f64 - mean).powi(2))
        .sum::<f64>()
        / n
}

/// The warnings a split of `train_ids` ids (`train_steps` steps) and `test_ids` ids
/// (`test_steps` steps) deserves: too few test ids ([`MIN_TEST_IDS`]), test steps
/// ([`MIN_TEST_STEPS`]) or training ids ([`MIN_TRAIN_IDS`]). Empty when it is big enough.
pub fn split_warnings(
    train_ids: usize,
    train_steps: usize,
    test_ids: usize,
    test_steps: usize,
) -> Vec<String> {
    let mut out = Vec::new();
    let advice = "use more ids (--test-fraction, --test-ids or --test-data)";
    if test_ids < MIN_TEST_IDS {
        out.push(format!(
            "only {test_ids} test id(s) (fewer than {MIN_TEST_IDS}): the MSEs describe those \
             sequences rather than the encoders, and the CIs cover only the seeds; {advice}"
        ));
    }
    if test_steps < MIN_TEST_STEPS {
        out.push(format!(
            "only {test_steps} test steps (fewer than {MIN_TEST_STEPS}): the MSEs are noisy; \
             {advice}"
        ));
    }
    if train_ids < MIN_TRAIN_IDS {
        out.push(format!(
            "only {train_ids} training id(s) ({train_steps} steps; fewer than {MIN_TRAIN_IDS} \
             ids): the heads can memorise them and fail on the test ids; {advice}"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn divergence_and_split_thresholds() {
        assert!(diverged(0.2, 0.08) && diverged(f64::NAN, 0.08) && !diverged(0.1, 0.08));
        assert!((time_variance(&[0.0, 1.0]) - 0.25).abs() < 1e-12);
        assert!(split_warnings(5, 500, 3, 100).is_empty());
        assert_eq!(split_warnings(4, 500, 2, 99).len(), 3);
    }
}
