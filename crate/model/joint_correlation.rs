use super::k_means::{nearest_centre, KMeans};
use super::ModelError;

/// How the errors of one step's joint values go together: the correlation of the model's
/// standardised errors, (truth − μ) / σ, at a step it imagines, fitted on sequences it did not
/// train on (`dmbn calibrate`). The network predicts each joint's Gaussian on its own; a push
/// that goes further moves every joint at once, so a future drawn with independent joints
/// wanders in directions no demonstration takes. Drawn as ε ~ N(0, R) (L ε with L Lᵀ = R, a
/// Gaussian copula on the network's marginals: Markou et al., "Practical Conditional Neural
/// Processes via Tractable Dependent Predictions", ICLR 2022), each joint keeps its predicted
/// mean and σ. A draw may keep only R's C leading principal directions
/// ([`JointCorrelation::correlate`]): where what is left open is a push's length or a carry's
/// spot, the errors' variation lies mostly along a few directions, and the rest is the
/// network's noise, which spoils a performed action.
///
/// A file may hold one R per **region** of the poses its futures reach (`dmbn calibrate
/// --regions`): the same joint errors mean different motions in different poses (a push's
/// length along the table, a held object's carry at its height), so one R pooled over both
/// moves the arm in directions neither takes (a carried object drawn higher or lower). Each
/// region is one action's drawn steps (at one drawn step of the future, or all), or a k-means
/// cluster of them, its centre their mean predicted pose (normalised); a draw takes the R of
/// the region whose centre is nearest the mean it is drawn around. Regions fitted per drawn
/// step also hold the steps' mean phase, and a draw looks only among those nearest its own:
/// at a carry's end the errors are its spot, a carry pose earlier they are mostly its timing,
/// and the two poses are too alike to tell apart.
#[derive(Debug, Clone, PartialEq)]
pub struct JointCorrelation {
    joints: usize,
    regions: Vec<Region>,
}

/// One region's R.
#[derive(Debug, Clone, PartialEq)]
struct Region {
    /// The mean pose (normalised joint values) of the steps it was fitted on, in f64 as the
    /// distances to it are taken; empty where the file holds one R.
    centre: Vec<f64>,
    /// The mean phase (0-1) of the steps it was fitted on, where its regions were fitted per
    /// drawn step.
    phase: Option<f32>,
    /// R, row-major `[D, D]`.
    values: Vec<f32>,
    /// R's principal factor, row-major `[D, D]`: column c is √λ_c v_c, the c-th largest
    /// eigenvalue and its unit eigenvector (so that the factor times its transpose is R).
    principal: Vec<f32>,
}

impl JointCorrelation {
    /// Off-diagonal values are shrunk towards 0 by this share when fitted, so that R stays
    /// positive definite where errors move together exactly (a joint that mirrors another).
    pub const SHRINKAGE: f64 = 0.01;
    /// At most this many regions.
    pub const MAX_REGIONS: usize = 16;
    /// How far from symmetric, or from a unit diagonal, a stored R may be (rounding).
    const TOLERANCE: f32 = 1e-4;
    /// Regions whose phases lie within this of the nearest one to a draw's phase count as
    /// fitted at its drawn step (the same step of sequences of other lengths, or of another
    /// action, falls at slightly other phases).
    pub const PHASE_TOLERANCE: f32 = 0.05;

    /// One R as stored (row-major, `joints` × `joints`): fails, naming `field`, unless it is
    /// a finite symmetric matrix of that size with a unit diagonal and positive definite.
    pub fn new(field: &str, values: Vec<f32>, joints: usize) -> Result<Self, ModelError> {
        Self::with_regions(field, values, None, None, joints)
    }

    /// K regions' R as stored (`values`: K × D × D, row-major) with their `centres` (K × D;
    /// needed where K > 1, and then finite) and, where they were fitted per drawn step, their
    /// `phases` (K, from 0 to 1): fails, naming `field`, unless each R is a correlation matrix
    /// as [`JointCorrelation::new`] checks.
    pub fn with_regions(
        field: &str,
        values: Vec<f32>,
        centres: Option<Vec<f32>>,
        phases: Option<Vec<f32>>,
        joints: usize,
    ) -> Result<Self, ModelError> {
        let bad = |what: String| ModelError::Header(format!("{field} {what}"));
        let per = joints * joints;
        let k = values.len().checked_div(per).unwrap_or(0);
        if k == 0 || k * per != values.len() || k > Self::MAX_REGIONS {
            return Err(bad(format!(
                "holds {} values: expected {joints} × {joints} (one row per joint value), or that for each of 1 to {} regions",
                values.len(),
                Self::MAX_REGIONS
            )));
        }
        let centres = match (k, centres) {
            (1, None) => vec![Vec::new()],
            (_, Some(c)) if c.len() == k * joints && c.iter().all(|v| v.is_finite()) => {
                c.chunks(joints).map(<[f32]>::to_vec).collect()
            }
            (_, c) => {
                return Err(ModelError::Header(format!(
                    "{field}_centres hold {}: expected {k} × {joints} finite values (a centre for each of its {k} regions)",
                    c.map_or("nothing".to_string(), |c| format!("{} values", c.len()))
                )))
            }
        };
        let phases: Vec<Option<f32>> = match phases {
            None => vec![None; k],
            Some(p) if k > 1 && p.len() == k && p.iter().all(|t| (0.0..=1.0).contains(t)) => {
                p.into_iter().map(Some).collect()
            }
            Some(p) => {
                return Err(ModelError::Header(format!(
                    "{field}_phases hold {} values: expected {k} phases from 0 to 1 (one for each of its regions, where there are 2 or more)",
                    p.len()
                )))
            }
        };
        let regions = (values.chunks(per).zip(centres).zip(phases))
            .enumerate()
            .map(|(r, ((values, centre), phase))| {
                let field = if k == 1 {
                    field.to_string()
                } else {
                    format!("{field} (region {r})")
                };
                Region::new(&field, values.to_vec(), centre, phase, joints)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(JointCorrelation { joints, regions })
    }

    /// The correlation of `errors` (rows of D standardised errors), shrunk by
    /// [`JointCorrelation::SHRINKAGE`]; a joint whose errors do not vary is uncorrelated.
    /// `None` with fewer than 2 rows.
    pub fn fit(errors: &[Vec<f32>], joints: usize) -> Option<Self> {
        let values = fit_values(errors, joints)?;
        JointCorrelation::new("the fitted correlation", values, joints).ok()
    }

    /// One R per region: the `regions` k-means clusters of `poses` (each error's predicted
    /// mean, normalised), R fitted on each cluster's errors as [`JointCorrelation::fit`].
    /// `None` where a cluster has fewer than 2 rows (or `regions` is 0 or above
    /// [`JointCorrelation::MAX_REGIONS`]).
    pub fn fit_regions(
        errors: &[Vec<f32>],
        poses: &[Vec<f32>],
        joints: usize,
        regions: usize,
    ) -> Option<Self> {
        if !(1..=Self::MAX_REGIONS.min(poses.len())).contains(&regions) {
            return None;
        }
        let labels = KMeans::fit(poses, regions).cluster;
        Self::fit_labelled(errors, poses, &labels, None, joints)
    }

    /// One R per label (`labels[i]` from 0 to K − 1, say the action each error comes from, or
    /// the action and drawn step), each region's centre the mean of its `poses` and, given
    /// each error's `phases`, its phase their mean: a draw takes the R of the label whose
    /// mean pose is nearest its own (among those of phases nearest its own). `None` where a
    /// label has fewer than 2 rows, the lengths differ, or K is above
    /// [`JointCorrelation::MAX_REGIONS`].
    pub fn fit_labelled(
        errors: &[Vec<f32>],
        poses: &[Vec<f32>],
        labels: &[usize],
        phases: Option<&[f32]>,
        joints: usize,
    ) -> Option<Self> {
        let k = labels.iter().max()? + 1;
        let n = errors.len();
        if poses.len() != n
            || labels.len() != n
            || phases.is_some_and(|p| p.len() != n)
            || k > Self::MAX_REGIONS
        {
            return None;
        }
        if k == 1 {
            return Self::fit(errors, joints);
        }
        let (mut values, mut centres, mut means) = (Vec::new(), Vec::new(), Vec::new());
        for c in 0..k {
            let members: Vec<usize> = (0..n).filter(|&i| labels[i] == c).collect();
            let rows: Vec<Vec<f32>> = members.iter().map(|&i| errors[i].clone()).collect();
            values.extend(fit_values(&rows, joints)?);
            centres.extend((0..joints).map(|j| {
                let sum: f64 = members.iter().map(|&i| poses[i][j] as f64).sum();
                (sum / members.len() as f64) as f32
            }));
            if let Some(p) = phases {
                let sum: f64 = members.iter().map(|&i| p[i] as f64).sum();
                means.push((sum / members.len() as f64) as f32);
            }
        }
        let phases = phases.map(|_| means);
        Self::with_regions(
            "the fitted correlation",
            values,
            Some(centres),
            phases,
            joints,
        )
        .ok()
    }

    /// D: joint values a step.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// K: regions, each with its own R (1: one R everywhere).
    pub fn regions(&self) -> usize {
        self.regions.len()
    }

    /// Every region's R, row-major K × D × D (the model file's `joint_correlation`).
    pub fn values(&self) -> Vec<f32> {
        (self.regions.iter())
            .flat_map(|r| r.values.iter().copied())
            .collect()
    }

    /// R of region `r`, row-major D × D.
    pub fn region_values(&self, r: usize) -> &[f32] {
        &self.regions[r].values
    }

    /// The regions' centres, K × D (the model file's `joint_correlation_centres`); `None`
    /// with one region.
    pub fn centres(&self) -> Option<Vec<f32>> {
        (self.regions.len() > 1).then(|| {
            (self.regions.iter())
                .flat_map(|r| r.centre.iter().map(|&v| v as f32))
                .collect()
        })
    }

    /// The regions' phases, K (the model file's `joint_correlation_phases`); `None` unless
    /// they were fitted per drawn step.
    pub fn phases(&self) -> Option<Vec<f32>> {
        self.regions.iter().map(|r| r.phase).collect()
    }

    /// The region a draw around `pose` (normalised joint values) at `phase` takes: the one
    /// whose centre is nearest, among those whose phase is within
    /// [`JointCorrelation::PHASE_TOLERANCE`] of the phase nearest `phase` where the regions
    /// have phases.
    pub fn region_of(&self, pose: &[f32], phase: f32) -> usize {
        let gap = |r: &Region| r.phase.map_or(0.0, |p| (p - phase).abs());
        let nearest = (self.regions.iter().map(gap)).fold(f32::INFINITY, f32::min);
        let candidates: Vec<usize> = (0..self.regions.len())
            // (A phase that is not a number keeps them all.)
            .filter(|&r| {
                let g = gap(&self.regions[r]);
                g.is_nan() || g <= nearest + Self::PHASE_TOLERANCE
            })
            .collect();
        let centres = candidates
            .iter()
            .map(|&r| self.regions[r].centre.as_slice());
        candidates[nearest_centre(centres, pose)]
    }

    /// D independent standard normal draws `eps` made to vary together as R of the region of
    /// `pose` at `phase` says ([`JointCorrelation::region_of`]), along its `components` leading
    /// principal directions (Σ_c √λ_c v_c ε_c over c < C; all D: the draws' correlation is R;
    /// fewer: the rest of the variation is left out). `eps[c]` drives direction c, so the same
    /// draws with fewer components are the same futures, pruned.
    pub fn correlate(&self, pose: &[f32], phase: f32, eps: &[f32], components: usize) -> Vec<f32> {
        let d = self.joints;
        let kept = components.min(d);
        let principal = &self.regions[self.region_of(pose, phase)].principal;
        (0..d)
            .map(|i| (0..kept).map(|c| principal[i * d + c] * eps[c]).sum())
            .collect()
    }
}

impl Region {
    fn new(
        field: &str,
        values: Vec<f32>,
        centre: Vec<f32>,
        phase: Option<f32>,
        joints: usize,
    ) -> Result<Self, ModelError> {
        let bad = |what: String| ModelError::Header(format!("{field} {what}"));
        for i in 0..joints {
            for j in 0..joints {
                let r = values[i * joints + j];
                if !r.is_finite() || r.abs() > 1.0 + JointCorrelation::TOLERANCE {
                    return Err(bad(format!(
                        "[{i}][{j}] is {r}: expected a correlation, from -1 to 1"
                    )));
                }
                if (r - values[j * joints + i]).abs() > JointCorrelation::TOLERANCE {
                    return Err(bad(format!("is not symmetric at [{i}][{j}]")));
                }
            }
            if (values[i * joints + i] - 1.0).abs() > JointCorrelation::TOLERANCE {
                return Err(bad(format!(
                    "[{i}][{i}] is {}: expected 1 on the diagonal",
                    values[i * joints + i]
                )));
            }
        }
        let eigen = symmetric_eigen(&values, joints);
        if eigen.last().is_some_and(|(lambda, _)| *lambda <= 1e-9) {
            return Err(bad(
                "is not positive definite: expected a correlation matrix".into(),
            ));
        }
        let mut principal = vec![0.0f32; joints * joints];
        for (c, (lambda, vector)) in eigen.iter().enumerate() {
            for (i, v) in vector.iter().enumerate() {
                principal[i * joints + c] = (lambda.sqrt() * v) as f32;
            }
        }
        Ok(Region {
            centre: centre.iter().map(|&v| v as f64).collect(),
            phase,
            values,
            principal,
        })
    }
}

/// R of `errors` (row-major D × D), shrunk by [`JointCorrelation::SHRINKAGE`]; `None` with
/// fewer than 2 rows or a row of another length.
fn fit_values(errors: &[Vec<f32>], joints: usize) -> Option<Vec<f32>> {
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
                covariance[i * joints + j] += (row[i] as f64 - mean[i]) * (row[j] as f64 - mean[j]);
            }
        }
    }
    let sd: Vec<f64> = (0..joints)
        .map(|i| covariance[i * joints + i].sqrt())
        .collect();
    Some(
        (0..joints * joints)
            .map(|k| {
                let (i, j) = (k / joints, k % joints);
                if i == j {
                    1.0
                } else if sd[i] > 1e-12 && sd[j] > 1e-12 {
                    ((1.0 - JointCorrelation::SHRINKAGE) * covariance[k] / (sd[i] * sd[j])) as f32
                } else {
                    0.0
                }
            })
            .collect(),
    )
}

/// The eigenvalues and unit eigenvectors of the symmetric `d` × `d` matrix `a`, largest first
/// (cyclic Jacobi rotations in f64, with + − × ÷ and √ alone: the same bits natively and in
/// wasm).
fn symmetric_eigen(a: &[f32], d: usize) -> Vec<(f64, Vec<f64>)> {
    let mut m: Vec<f64> = a.iter().map(|&x| x as f64).collect();
    let mut v: Vec<f64> = (0..d * d)
        .map(|k| if k / d == k % d { 1.0 } else { 0.0 })
        .collect();
    for _sweep in 0..100 {
        let off: f64 = (0..d * d)
            .filter(|k| k / d != k % d)
            .map(|k| m[k] * m[k])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..d {
            for q in p + 1..d {
                let apq = m[p * d + q];
                if apq == 0.0 {
                    continue;
                }
                // The rotation J that zeroes m[p][q]: m ← Jᵀ m J, v ← v J.
                let theta = (m[q * d + q] - m[p * d + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..d {
                    let (kp, kq) = (m[k * d + p], m[k * d + q]);
                    m[k * d + p] = c * kp - s * kq;
                    m[k * d + q] = s * kp + c * kq;
                }
                for k in 0..d {
                    let (pk, qk) = (m[p * d + k], m[q * d + k]);
                    m[p * d + k] = c * pk - s * qk;
                    m[q * d + k] = s * pk + c * qk;
                }
                for k in 0..d {
                    let (kp, kq) = (v[k * d + p], v[k * d + q]);
                    v[k * d + p] = c * kp - s * kq;
                    v[k * d + q] = s * kp + c * kq;
                }
            }
        }
    }
    let mut pairs: Vec<(f64, Vec<f64>)> = (0..d)
        .map(|c| (m[c * d + c], (0..d).map(|i| v[i * d + c]).collect()))
        .collect();
    pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
    pairs
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
        // The principal factor times its transpose is R.
        let l = &r.regions[0].principal;
        for i in 0..4 {
            for j in 0..4 {
                let llt: f32 = (0..4).map(|k| l[i * 4 + k] * l[j * 4 + k]).sum();
                assert!((llt - v[i * 4 + j]).abs() < 1e-5, "{i} {j}");
            }
        }
        // The leading direction moves the first three together (the third against), the
        // fourth not at all: the first and the third go against each other.
        let x = r.correlate(&[], 0.5, &[1.0, 0.0, 0.0, 0.0], 4);
        assert!(x[0] * x[2] < 0.0 && x[3].abs() < 1e-6, "{x:?}");
        assert!((x[0] + x[2]).abs() < 0.05 * x[0].abs(), "{x:?}");
        // One component: whatever the other draws, only the leading direction moves.
        assert_eq!(r.correlate(&[], 0.5, &[1.0, 5.0, -3.0, 2.0], 1), x);
    }

    #[test]
    fn each_region_draws_with_its_own_correlation() {
        // Two places the arm reaches: near pose [0, 0] the errors of the first two joints go
        // together, near [5, 5] against each other. Pooled they cancel out; in regions each
        // keeps its own.
        let (mut errors, mut poses) = (Vec::new(), Vec::new());
        for i in 0..400 {
            let a = ((i * 37 % 101) as f32 / 50.0) - 1.0;
            let b = ((i * 53 % 97) as f32 / 48.0) - 1.0;
            let near = i % 2 == 0;
            errors.push(vec![a, if near { a } else { -a } + 0.1 * b]);
            let at = if near { 0.0 } else { 5.0 };
            poses.push(vec![at + 0.01 * b, at]);
        }
        let pooled = JointCorrelation::fit(&errors, 2).unwrap();
        assert!(pooled.values()[1].abs() < 0.2, "{:?}", pooled.values());
        let r = JointCorrelation::fit_regions(&errors, &poses, 2, 2).unwrap();
        assert_eq!(r.regions(), 2);
        let (near, far) = (r.region_of(&[0.2, 0.1], 0.5), r.region_of(&[4.0, 6.0], 0.5));
        assert_ne!(near, far);
        assert!(r.region_values(near)[1] > 0.95 && r.region_values(far)[1] < -0.95);
        let x = r.correlate(&[0.0, 0.0], 0.5, &[1.0, 0.0], 1);
        let y = r.correlate(&[5.0, 5.0], 0.5, &[1.0, 0.0], 1);
        assert!(x[0] * x[1] > 0.0 && y[0] * y[1] < 0.0, "{x:?} {y:?}");
        // Stored and read back: the same regions, the same draws.
        let centres = r.centres().unwrap();
        assert_eq!(centres.len(), 4);
        let back = JointCorrelation::with_regions("r", r.values(), Some(centres), None, 2).unwrap();
        assert_eq!(back, r);
        // Too few rows for a region, or no centres for several: refused.
        assert!(JointCorrelation::fit_regions(&errors[..3], &poses[..3], 2, 4).is_none());
        let err = JointCorrelation::with_regions("joint_correlation", r.values(), None, None, 2);
        assert!(err
            .unwrap_err()
            .to_string()
            .contains("expected 2 × 2 finite values"));
    }

    #[test]
    fn regions_fitted_per_drawn_step_are_chosen_by_phase_then_pose() {
        // One pose, two drawn steps: at phase 0.6 the errors go together, at 1 against each
        // other. The pose alone cannot tell them apart; the phase does.
        let (mut errors, mut poses, mut labels, mut phases) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..400 {
            let a = ((i * 37 % 101) as f32 / 50.0) - 1.0;
            let b = ((i * 53 % 97) as f32 / 48.0) - 1.0;
            let end = i % 2 == 1;
            errors.push(vec![a, if end { -a } else { a } + 0.1 * b]);
            poses.push(vec![0.01 * b, 0.0]);
            labels.push(end as usize);
            // Sequences of other lengths: the same drawn step at slightly other phases.
            phases.push(if end { 1.0 } else { 0.6 + 0.02 * b });
        }
        let r = JointCorrelation::fit_labelled(&errors, &poses, &labels, Some(&phases), 2).unwrap();
        let stored = r.phases().unwrap();
        assert!(
            (stored[0] - 0.6).abs() < 0.01 && stored[1] == 1.0,
            "{stored:?}"
        );
        assert_eq!(
            (
                r.region_of(&[0.0, 0.0], 0.62),
                r.region_of(&[0.0, 0.0], 0.97)
            ),
            (0, 1)
        );
        assert!(r.region_of(&[0.0, 0.0], f32::NAN) < 2);
        assert!(r.region_values(0)[1] > 0.95 && r.region_values(1)[1] < -0.95);
        let back = JointCorrelation::with_regions("r", r.values(), r.centres(), r.phases(), 2);
        assert_eq!(back.unwrap(), r);
        // Phases that are not one per region, or not from 0 to 1: refused by name.
        for phases in [vec![0.6], vec![0.6, 1.5]] {
            let err = JointCorrelation::with_regions(
                "joint_correlation",
                r.values(),
                r.centres(),
                Some(phases),
                2,
            );
            assert!(err
                .unwrap_err()
                .to_string()
                .contains("joint_correlation_phases hold"));
        }
        // Without phases: no phases stored.
        assert!(
            JointCorrelation::fit_labelled(&errors, &poses, &labels, None, 2)
                .unwrap()
                .phases()
                .is_none()
        );
    }

    #[test]
    fn eigenpairs_come_largest_first_and_rebuild_the_matrix() {
        let eigen = symmetric_eigen(&[2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.5], 3);
        let lambdas: Vec<f64> = eigen.iter().map(|(l, _)| *l).collect();
        for (got, want) in lambdas.iter().zip([3.0, 1.0, 0.5]) {
            assert!((got - want).abs() < 1e-12, "{lambdas:?}");
        }
        let (_, top) = &eigen[0];
        assert!((top[0].abs() - 0.5f64.sqrt()).abs() < 1e-12 && top[0] * top[1] > 0.0);
        assert!(top[2].abs() < 1e-12);
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
