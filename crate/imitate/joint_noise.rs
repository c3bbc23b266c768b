use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Smooth noise on `joints` arm joints, `steps` rows: per joint a sum of four sinusoids of 0.5-2
/// cycles over the episode (random phases and weights, drawn from `seed`), scaled so that its
/// RMSE over the steps is `rmse` radians. Added to a demonstration's recorded joints it asks
/// how much error of the kind a model makes (slow, not jitter) the action tolerates.
pub fn joint_noise(steps: usize, joints: usize, rmse: f32, seed: u64) -> Vec<Vec<f32>> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut rows = vec![vec![0.0f32; joints]; steps];
    for j in 0..joints {
        let waves: Vec<[f32; 3]> = (0..4)
            .map(|_| {
                [
                    rng.random_range(0.5f32..2.0),
                    rng.random_range(0.0f32..core::f32::consts::TAU),
                    rng.random_range(-1.0f32..1.0),
                ]
            })
            .collect();
        let curve: Vec<f32> = (0..steps)
            .map(|k| {
                let phase = k as f32 / (steps.max(2) - 1) as f32;
                waves
                    .iter()
                    .map(|[cycles, offset, weight]| {
                        weight * libm::sinf(core::f32::consts::TAU * cycles * phase + offset)
                    })
                    .sum()
            })
            .collect();
        let rms = (curve.iter().map(|v| v * v).sum::<f32>() / steps.max(1) as f32).sqrt();
        for (row, v) in rows.iter_mut().zip(&curve) {
            row[j] = if rms > 0.0 { v / rms * rmse } else { 0.0 };
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_has_the_rmse_asked_for_and_is_smooth() {
        let n = joint_noise(80, 6, 0.01, 3);
        assert_eq!(n.len(), 80);
        assert!(n.iter().all(|r| r.len() == 6));
        for j in 0..6 {
            let rms = (n.iter().map(|r| r[j] * r[j]).sum::<f32>() / 80.0).sqrt();
            assert!((rms - 0.01).abs() < 1e-5, "joint {j}: {rms}");
            // At most 2 cycles over 80 steps: a step moves it a small part of its range.
            let jump = n
                .windows(2)
                .map(|w| (w[1][j] - w[0][j]).abs())
                .fold(0.0, f32::max);
            assert!(jump < 0.01 * 0.5, "joint {j}: a step of {jump}");
        }
        assert_eq!(
            n,
            joint_noise(80, 6, 0.01, 3),
            "the same seed, the same noise"
        );
        assert_ne!(n, joint_noise(80, 6, 0.01, 4));
        assert!(joint_noise(0, 6, 0.01, 3).is_empty());
        assert_eq!(joint_noise(1, 6, 0.01, 3).len(), 1);
        // Another arm's joint count: the first joints' noise is the same.
        let seven = joint_noise(80, 7, 0.01, 3);
        assert!(seven.iter().zip(&n).all(|(a, b)| a[..6] == b[..]));
    }
}
