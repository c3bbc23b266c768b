use super::ModelError;

/// How the errors of one step's joint values go together: the correlation of the model's
/// standardised errors, (truth − μ) / σ, at a step it imagines, fitted on sequences it did not
/// train on (`dmbn calibrate`). The network predicts each joint's Gaussian on its own; a push
/// that goes further moves every joint at once, so a future drawn with independent joints
/// wanders in directions no demonstration takes. Drawn as ε ~ N(0, R) (L ε with L Lᵀ = R, a
/// Gaussian copula on the network's marginals: Markou et al., "Practical Conditional Neural
/// Processes via Tractable Dependent Predictions", ICLR 2022), each joint keeps its predicted
/// mean and σ.
#[derive(Debug, Clone, PartialEq)]
pub struct JointCorrelation {
    joints: usize,
    /// R, row-major `[D, D]`.
    values: Vec<f32>,
    /// L, its lower Cholesky factor, row-major `[D, D]`.
    cholesky: Vec<f32>,
}

impl JointCorrelation {
    /// Off-diagonal values are shrunk towards 0 by this share when fitted, so that R stays
    /// positive definite where errors move together exactly (a joint that mirrors another).
    pub const SHRINKAGE: f64 = 0.01;
    /// How far from symmetric, or from a unit diagonal, a stored R may be (rounding).
    const TOLERANCE: f32 = 1e-4;

    /// R as stored (row-major, `joints` × `joints`): fails, naming `field`, unless it is a
    /// finite symmetric matrix of that size with a unit diagonal and positive definite.
    pub fn new(field: &str, values: Vec<f32>, joints: usize) -> Result<Self, ModelError> {
        let bad = |what: String| ModelError::Header(format!("{field} {what}"));
        if values.len() != joints * joints {
            return Err(bad(format!(
                "holds {} values: expected {joints} × {joints} (one row per joint value)",
                values.len()
            )));
        }
        for i in 0..joints {
            for j in 0..joints {
                let r = values[i * joints + j];
                if !r.is_finite() || r.abs() > 1.0 + Self::TOLERANCE {
                    return Err(bad(format!(
                        "[{i}][{j}] is {r}: expected a correlation, from -1 to 1"
                    )));
                }
                if (r - values[j * joints + i]).abs() > Self::TOLERANCE {
                    return Err(bad(format!("is not symmetric at [{i}][{j}]")));
                }
            }
            if (values[i * joints + i] - 1.0).abs() > Self::TOLERANCE {
                return Err(bad(format!(
                    "[{i}][{i}] is {}: expected 1 on the diagonal",
                    values[i * joints + i]
                )));
            }
        }
        let cholesky = cholesky(&values, joints)
            .ok_or_else(|| bad("is not positive definite: expected a correlation matrix".into()))?;
        Ok(JointCorrelation {
            joints,
            values,
            cholesky,
        })
    }

    /// The correlation of `errors` (rows of D standardised errors), shrunk by
    /// [`JointCorrelation::SHRINKAGE`]; a joint whose errors do not vary is uncorrelated.
    /// `None` with fewer than 2 rows.
    pub fn fit(errors: &[Vec<f32>], joints: usize) -> Option<Self> {
        let n = errors.len();
        if n < 2 || errors.iter().any(|row| row.len() != joints) {
            return None;
        }
        let mean: Vec<f64> = (0..joints)
            .map(|j| errors.iter().map(|row| row[j] as f64).sum::<f64>() / n as f64)
            .collect();
        let mut covariance = vec![0.0f64; joints * joints];
        for row in errors {
            for i in 0..joints {
                for j in 0..joints {
                    covariance[i * joints + j] +=
                        (row[i] as f64 - mean[i]) * (row[j] as f64 - mean[j]);
                }
            }
        }
        let sd: Vec<f64> = (0..joints)
            .map(|i| covariance[i * joints + i].sqrt())
            .collect();
        let values = (0..joints * joints)
            .map(|k| {
                let (i, j) = (k / joints, k % joints);
                if i == j {
                    1.0
                } else if sd[i] > 1e-12 && sd[j] > 1e-12 {
                    ((1.0 - Self::SHRINKAGE) * covariance[k] / (sd[i] * sd[j])) as f32
                } else {
                    0.0
                }
            })
            .collect();
        JointCorrelation::new("the fitted correlation", values, joints).ok()
    }

    /// D: joint values a step.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// R, row-major (the model file's `joint_correlation`).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// L ε: D independent standard normal draws made to vary together as R says.
    pub fn correlate(&self, eps: &[f32]) -> Vec<f32> {
        let d = self.joints;
        (0..d)
            .map(|i| (0..=i).map(|j| self.cholesky[i * d + j] * eps[j]).sum())
            .collect()
    }
}

/// The lower Cholesky factor of the `d` × `d` matrix `a` (in f64, stored as f32: the same
/// bits natively and in wasm); `None` unless `a` is positive definite.
fn cholesky(a: &[f32], d: usize) -> Option<Vec<f32>> {
    let mut l = vec![0.0f64; d * d];
    for i in 0..d {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * d + k] * l[j * d + k]).sum();
            let v = a[i * d + j] as f64 - s;
            if i == j {
                if v <= 1e-9 {
                    return None;
                }
                l[i * d + i] = v.sqrt();
            } else {
                l[i * d + j] = v / l[j * d + j];
            }
        }
    }
    Some(l.into_iter().map(|v| v as f32).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn correlated_draws_have_the_fitted_correlation() {
        // Errors that move together: the second is the first plus a little noise, the third
        // goes against the first, the fourth never varies.
        let mut state = 7u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let rows: Vec<Vec<f32>> = (0..4000)
            .map(|_| {
                let (a, b) = (uniform(), uniform());
                vec![a, a + 0.3 * b, -a, 0.0]
            })
            .collect();
        let r = JointCorrelation::fit(&rows, 4).unwrap();
        let v = r.values();
        assert!(v[1] > 0.9 && v[1] < 0.99, "{v:?}");
        assert!(v[2] < -0.98, "{v:?}");
        assert_eq!((v[3], v[15]), (0.0, 1.0));
        // L Lᵀ = R.
        let l = &r.cholesky;
        for i in 0..4 {
            for j in 0..4 {
                let llt: f32 = (0..4).map(|k| l[i * 4 + k] * l[j * 4 + k]).sum();
                assert!((llt - v[i * 4 + j]).abs() < 1e-5, "{i} {j}");
            }
        }
        // Independent draws correlated: the first and the third now go against each other.
        let x = r.correlate(&[1.0, 0.0, 0.0, 0.0]);
        assert!(x[0] > 0.99 && x[2] < -0.98, "{x:?}");
    }

    #[test]
    fn a_bad_matrix_is_refused_by_name() {
        let err = |values: Vec<f32>, d| {
            JointCorrelation::new("joint_correlation", values, d)
                .unwrap_err()
                .to_string()
        };
        assert!(err(vec![1.0; 3], 2).contains("expected 2 × 2"));
        assert!(err(vec![1.0, 0.5, 0.4, 1.0], 2).contains("not symmetric"));
        assert!(err(vec![2.0, 0.0, 0.0, 1.0], 2).contains("from -1 to 1"));
        assert!(err(vec![0.5, 0.0, 0.0, 1.0], 2).contains("1 on the diagonal"));
        assert!(err(vec![1.0, 1.0, 1.0, 1.0], 2).contains("not positive definite"));
        assert!(err(vec![1.0, f32::NAN, f32::NAN, 1.0], 2).contains("joint_correlation"));
        assert!(JointCorrelation::fit(&[vec![1.0, 2.0]], 2).is_none());
        JointCorrelation::new("r", vec![1.0, -0.5, -0.5, 1.0], 2).unwrap();
    }
}
