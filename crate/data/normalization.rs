use serde::{Deserialize, Serialize};

use super::JointScale;

/// Joint normalisation statistics of a dataset: the model sees `(joint - mean) / std` per
/// column and predicts in that space. Saved in the model file, so predictions can be mapped
/// back to radians (and gripper units) with the statistics the model was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalization {
    /// Per-column mean of the D joint values (the original's: 6 arm angles, gripper).
    pub mean: Vec<f32>,
    /// Per-column standard deviation, strictly positive.
    pub std: Vec<f32>,
}

impl Normalization {
    /// Standard deviations below this are replaced by 1 in [`Normalization::fit`] (a column
    /// that never moves, such as the gripper of a move-only dataset).
    pub const MIN_STD: f32 = 1e-6;

    /// Mean 0 and standard deviation 1 for `width` values: joints are used as they are.
    pub fn identity(width: usize) -> Self {
        Self {
            mean: vec![0.0; width],
            std: vec![1.0; width],
        }
    }

    /// Values a step (D).
    pub fn width(&self) -> usize {
        self.mean.len()
    }

    /// Column means and (population) standard deviations of joint rows of `width` values.
    /// A column whose standard deviation is below [`Normalization::MIN_STD`] gets 1, so it is
    /// only centred. No rows gives the identity.
    pub fn fit<'a>(width: usize, rows: impl IntoIterator<Item = &'a [f32]>) -> Self {
        let mut count = 0.0f64;
        let mut sum = vec![0.0f64; width];
        let mut sum_sq = vec![0.0f64; width];
        for row in rows {
            assert_eq!(row.len(), width, "a joint row of another width");
            count += 1.0;
            for (j, &v) in row.iter().enumerate() {
                sum[j] += v as f64;
                sum_sq[j] += v as f64 * v as f64;
            }
        }
        if count == 0.0 {
            return Self::identity(width);
        }
        let mut out = Self::identity(width);
        for j in 0..width {
            let mean = sum[j] / count;
            let var = (sum_sq[j] / count - mean * mean).max(0.0);
            out.mean[j] = mean as f32;
            let std = var.sqrt() as f32;
            out.std[j] = if std < Self::MIN_STD { 1.0 } else { std };
        }
        out
    }

    /// These statistics with the arm angles' scale chosen by `scale`: for
    /// [`JointScale::Shared`], one standard deviation for all values but the last (the root
    /// mean square of theirs), the last's (the gripper's, by the layout's convention) unchanged.
    pub fn scaled(mut self, scale: JointScale) -> Self {
        if scale == JointScale::Shared && self.width() > 0 {
            let n = super::arm_joints(self.width());
            let arm = &mut self.std[..n];
            let shared = (arm.iter().map(|s| s * s).sum::<f32>() / arm.len() as f32).sqrt();
            arm.fill(shared);
        }
        self
    }

    /// `(joints - mean) / std`, column by column.
    pub fn normalize(&self, joints: &[f32]) -> Vec<f32> {
        (0..self.width())
            .map(|j| (joints[j] - self.mean[j]) / self.std[j])
            .collect()
    }

    /// Mean squared normalised value over every joint of `rows`: how many (squared) standard
    /// deviations joints lie from the data these statistics come from. The page offers, for a
    /// folder, the models whose normalisation its joints fit best. Infinite without rows.
    pub fn distance<'a>(&self, rows: impl IntoIterator<Item = &'a [f32]>) -> f64 {
        let (mut sum, mut n) = (0.0f64, 0usize);
        for row in rows {
            sum += self
                .normalize(row)
                .iter()
                .map(|z| f64::from(*z).powi(2))
                .sum::<f64>();
            n += self.width();
        }
        if n == 0 {
            f64::INFINITY
        } else {
            sum / n as f64
        }
    }

    /// `joints * std + mean`: back from model space to joint units.
    pub fn denormalize(&self, joints: &[f32]) -> Vec<f32> {
        (0..self.width())
            .map(|j| joints[j] * self.std[j] + self.mean[j])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_normalize_denormalize() {
        let rows = [
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0],
            [3.0, 2.0, 5.0, 4.0, 5.0, 6.0, 0.0],
        ];
        let n = Normalization::fit(7, rows.iter().map(|r| &r[..]));
        assert_eq!(n.mean[0], 2.0);
        assert_eq!(n.std[0], 1.0);
        assert_eq!(n.std[1], 1.0, "constant column gets std 1");
        assert_eq!(n.mean[1], 2.0);
        let z = n.normalize(&rows[1]);
        assert_eq!(z[0], 1.0);
        assert_eq!(z[1], 0.0);
        let back = n.denormalize(&z);
        assert_eq!(back, rows[1]);
        assert_eq!(n.distance(rows.iter().map(|r| &r[..])), 2.0 / 7.0);
        assert_eq!(n.distance([]), f64::INFINITY);
    }

    #[test]
    fn a_shared_scale_is_the_arm_s_root_mean_square_and_keeps_the_gripper_s() {
        let n = Normalization {
            mean: vec![1.0; 7],
            std: vec![1.0, 1.0, 1.0, 1.0, 7.0, 1.0, 0.5],
        };
        assert_eq!(n.clone().scaled(JointScale::PerJoint), n);
        let shared = n.clone().scaled(JointScale::Shared);
        assert_eq!(shared.mean, n.mean);
        assert_eq!(shared.std, [3.0, 3.0, 3.0, 3.0, 3.0, 3.0, 0.5]);
        // Three values: the first two share, the last keeps its own.
        let three = Normalization {
            mean: vec![0.0; 3],
            std: vec![1.0, 7.0, 0.5],
        };
        assert_eq!(three.scaled(JointScale::Shared).std, [5.0, 5.0, 0.5]);
    }
}
