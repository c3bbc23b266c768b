use burn::nn::loss::GaussianNLLLossConfig;
use burn::tensor::Tensor;

use super::Prediction;

/// The training objective and its parts, as 1-element tensors: `total` carries the graph for
/// `backward`, the parts are detached (for metrics).
#[derive(Debug, Clone)]
pub struct Loss {
    /// image_nll + joint_weight · joint_nll.
    pub total: Tensor<1>,
    /// Gaussian NLL of the target frames, mean over pixels, channels, targets and sequences.
    pub image_nll: Tensor<1>,
    /// Gaussian NLL of the target joints, mean over joints, targets and sequences.
    pub joint_nll: Tensor<1>,
    /// Mean squared error of the predicted mean frames.
    pub image_mse: Tensor<1>,
    /// Mean squared error of the predicted mean joints (normalised units).
    pub joint_mse: Tensor<1>,
}

/// [`Loss`] read back as numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossValues {
    /// image_nll + joint_weight · joint_nll.
    pub total: f32,
    /// Gaussian NLL of the frames, per value.
    pub image_nll: f32,
    /// Gaussian NLL of the joints, per value.
    pub joint_nll: f32,
    /// Mean squared error of the mean frames.
    pub image_mse: f32,
    /// Mean squared error of the mean joints.
    pub joint_mse: f32,
}

impl Loss {
    /// All five values, in one read from the device.
    pub fn values(&self) -> LossValues {
        let all = Tensor::cat(
            vec![
                self.total.clone().detach(),
                self.image_nll.clone(),
                self.joint_nll.clone(),
                self.image_mse.clone(),
                self.joint_mse.clone(),
            ],
            0,
        );
        let v: Vec<f32> = all
            .into_data()
            .convert::<f32>()
            .try_to_vec()
            .unwrap_or_default();
        let at = |i: usize| v.get(i).copied().unwrap_or(f32::NAN);
        LossValues {
            total: at(0),
            image_nll: at(1),
            joint_nll: at(2),
            image_mse: at(3),
            joint_mse: at(4),
        }
    }
}

/// The Gaussian negative log-likelihood of the targets under the prediction, per value:
/// `½·log(2π) + log σ + (x − μ)² / (2σ²)` (burn's `GaussianNLLLoss` with the constant, so the
/// numbers are true negative log-densities in nats), averaged over every value of a
/// modality, then `total = image_nll + joint_weight · joint_nll`.
///
/// Shapes: `target_images` `[B, M, 3, S, S]`, `target_joints` `[B, M, 7]`, as the prediction.
pub fn gaussian_loss(
    prediction: &Prediction,
    target_images: Tensor<5>,
    target_joints: Tensor<3>,
    joint_weight: f64,
) -> Loss {
    let nll = GaussianNLLLossConfig::new().with_full(true).init();
    let image_nll = nll
        .forward_no_reduction(
            prediction.image_mean.clone(),
            target_images.clone(),
            prediction.image_sigma.clone().square(),
        )
        .mean();
    let joint_nll = joint_nll(
        prediction.joint_mean.clone(),
        prediction.joint_sigma.clone(),
        target_joints.clone(),
    );
    let total = image_nll.clone() + joint_nll.clone().mul_scalar(joint_weight);
    let image_mse = (prediction.image_mean.clone().detach() - target_images)
        .square()
        .mean();
    let joint_mse = (prediction.joint_mean.clone().detach() - target_joints)
        .square()
        .mean();
    Loss {
        total,
        image_nll: image_nll.detach(),
        joint_nll: joint_nll.detach(),
        image_mse,
        joint_mse,
    }
}

/// The Gaussian NLL of `target` joints under `mean` and `sigma` (all `[B, M, 7]`), per value.
pub fn joint_nll(mean: Tensor<3>, sigma: Tensor<3>, target: Tensor<3>) -> Tensor<1> {
    GaussianNLLLossConfig::new()
        .with_full(true)
        .init()
        .forward_no_reduction(mean, target, sigma.square())
        .mean()
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Device;

    #[test]
    fn nll_matches_the_formula() {
        let device = Device::flex();
        let prediction = Prediction {
            image_mean: Tensor::full([1, 1, 3, 2, 2], 0.5, &device),
            image_sigma: Tensor::full([1, 1, 3, 2, 2], 0.1, &device),
            image_drawn: None,
            joint_mean: Tensor::zeros([1, 1, 7], &device),
            joint_sigma: Tensor::ones([1, 1, 7], &device),
        };
        let images = Tensor::full([1, 1, 3, 2, 2], 0.7, &device);
        let joints = Tensor::full([1, 1, 7], 2.0, &device);
        let v = gaussian_loss(&prediction, images, joints, 0.5).values();
        let half_log_2pi = 0.5 * (2.0 * std::f32::consts::PI).ln();
        let image = half_log_2pi + 0.1f32.ln() + 0.04 / (2.0 * 0.01);
        let joint = half_log_2pi + 2.0;
        assert!((v.image_nll - image).abs() < 1e-4, "{v:?} vs {image}");
        assert!((v.joint_nll - joint).abs() < 1e-5, "{v:?} vs {joint}");
        assert!((v.total - (image + 0.5 * joint)).abs() < 1e-4);
        assert!((v.image_mse - 0.04).abs() < 1e-6);
        assert!((v.joint_mse - 4.0).abs() < 1e-6);
    }
}
