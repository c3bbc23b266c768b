//! The probe's input standardisation (see [`Standardizer`]).

/// Per-feature standardisation of the probe's inputs, fitted on the training encodings and
/// built so that no feature can blow up. A feature whose standard deviation on the training
/// steps is below [`REL_STD_FLOOR`] of the encoding's median feature deviation (or below
/// [`ABS_STD_FLOOR`]) is near-constant: it is scaled by that floor instead, and its test
/// values are clipped to the range it took on the training steps, so that a feature the
/// head could learn nothing about cannot feed it values it never saw (before, a feature of
/// deviation 1e-5 on the training ids put test values 1e5 deviations out). Every standardised
/// value is clipped to ±[`STANDARD_CLIP`]; non-finite values count as the feature's mean.
/// Other features are standardised as usual (their test values may leave the training
/// range: a shift of the test ids' encodings is what the head has to extrapolate over).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Standardizer {
    mean: Vec<f32>,
    scale: Vec<f32>,
    /// Test-time bounds per feature (±[`STANDARD_CLIP`] unless near-constant).
    lo: Vec<f32>,
    hi: Vec<f32>,
}

/// A feature whose deviation is below this fraction of the median feature deviation of its
/// encoding is near-constant (see `Standardizer`).
pub const REL_STD_FLOOR: f32 = 0.05;
/// ... as is one below this, whatever the encoding's scale.
pub const ABS_STD_FLOOR: f32 = 1e-6;
/// Standardised values are clipped to ±this.
pub const STANDARD_CLIP: f32 = 10.0;

impl Standardizer {
    /// Statistics of the `n × h` row-major `x`.
    pub(super) fn fit(x: &[f32], h: usize) -> Standardizer {
        let rows = || x.chunks_exact(h.max(1));
        let mut mean = vec![0.0f32; h];
        let mut std = vec![0.0f32; h];
        for j in 0..h {
            let col = || rows().map(|r| r[j]).filter(|v| v.is_finite());
            let count = col().count().max(1) as f64;
            let m = col().map(|v| v as f64).sum::<f64>() / count;
            let var = col().map(|v| (v as f64 - m).powi(2)).sum::<f64>() / count;
            mean[j] = m as f32;
            std[j] = var.sqrt() as f32;
        }
        let mut sorted = std.clone();
        sorted.sort_by(f32::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let typical = if median > 0.0 {
            median
        } else {
            sorted.iter().sum::<f32>() / sorted.len().max(1) as f32
        };
        let floor = (REL_STD_FLOOR * typical).max(ABS_STD_FLOOR);
        let near_constant: Vec<bool> = std.iter().map(|&s| s.is_nan() || s < floor).collect();
        let mut out = Standardizer {
            mean,
            scale: std.iter().map(|&s| s.max(floor)).collect(),
            lo: vec![-STANDARD_CLIP; h],
            hi: vec![STANDARD_CLIP; h],
        };
        let (mut lo, mut hi) = (vec![f32::INFINITY; h], vec![f32::NEG_INFINITY; h]);
        for row in rows() {
            for (j, &v) in row.iter().enumerate() {
                let z = out.standard(j, v);
                lo[j] = lo[j].min(z);
                hi[j] = hi[j].max(z);
            }
        }
        for j in 0..h {
            if near_constant[j] && lo[j] <= hi[j] {
                out.lo[j] = lo[j];
                out.hi[j] = hi[j];
            }
        }
        out
    }

    /// Feature `j` of value `v` standardised and clipped to ±[`STANDARD_CLIP`].
    fn standard(&self, j: usize, v: f32) -> f32 {
        if !v.is_finite() {
            return 0.0;
        }
        ((v - self.mean[j]) / self.scale[j]).clamp(-STANDARD_CLIP, STANDARD_CLIP)
    }

    /// Standardises the rows of `x` in place; with `test` also clips each feature to its
    /// test-time bounds.
    pub(super) fn apply(&self, x: &mut [f32], test: bool) {
        let h = self.mean.len();
        for row in x.chunks_exact_mut(h.max(1)) {
            for (j, v) in row.iter_mut().enumerate() {
                let z = self.standard(j, *v);
                *v = if test {
                    z.clamp(self.lo[j], self.hi[j])
                } else {
                    z
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standardizer_scales_healthy_features_and_pins_near_constant_ones() {
        // Features: k and 2k (std √1.25 and 2√1.25), 5 but for a 1e-6 jitter, constant 0.
        let mut train = Vec::new();
        for k in 0..4 {
            let jitter = if k == 2 { 1e-6 } else { 0.0 };
            train.extend([k as f32, 2.0 * k as f32, 5.0 + jitter, 0.0]);
        }
        let st = Standardizer::fit(&train, 4);
        let mut x = train.clone();
        st.apply(&mut x, false);
        let s0 = 1.25f32.sqrt();
        for (k, v) in x.chunks(4).enumerate() {
            let z = (k as f32 - 1.5) / s0;
            assert!((v[0] - z).abs() < 1e-5 && (v[1] - z).abs() < 1e-5, "{v:?}");
            assert!(v[2].abs() < 1e-4 && v[3] == 0.0, "{v:?}");
        }
        // Test values far off: the healthy features are standardised (clipped at ±10), the
        // near-constant ones stay in the range they had on the training steps.
        let mut test = vec![4.5, 1e9, 7.0, -3.0, f32::NAN, -1.0, -1e9, f32::INFINITY];
        st.apply(&mut test, true);
        assert!((test[0] - 3.0 / s0).abs() < 1e-5, "{test:?}");
        assert_eq!((test[1], test[4]), (STANDARD_CLIP, 0.0), "{test:?}");
        assert!((test[5] + 4.0 / (2.0 * s0)).abs() < 1e-5, "{test:?}");
        for v in [test[2], test[3], test[6], test[7]] {
            assert!(v.abs() < 1e-4, "{test:?}");
        }
    }
}
