use burn::nn::loss::GaussianNLLLossConfig;
use burn::tensor::Tensor;

use super::Prediction;

/// The training objective and its parts, as 1-element tensors: `total` carries the graph for
/// `backward`, the parts are detached (for metrics).
#[derive(Debug, Clone)]
pub struct Loss {
    /// image_nll + joint_weight · joint_nll, as β-NLL when β > 0 (see [`gaussian_loss`]).
    pub total: Tensor<1>,
    /// Gaussian NLL of the target frames, mean over pixels, channels, targets and sequences.
    pub image_nll: Tensor<1>,
    /// Gaussian NLL of the target joints, mean over joints, targets and sequences.
    pub joint_nll: Tensor<1>,
    /// Mean squared error of the predicted mean frames.
    pub image_mse: Tensor<1>,
    /// Mean squared error of the predicted mean joints (normalised units).
    pub joint_mse: Tensor<1>,
    /// A model with a latent path, in training: KL(posterior ‖ prior) of z, nats per sequence.
    pub kl: Option<Tensor<1>>,
}

/// [`Loss`] read back as numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossValues {
    /// image_nll + joint_weight · joint_nll, as β-NLL when β > 0.
    pub total: f32,
    /// Gaussian NLL of the frames, per value.
    pub image_nll: f32,
    /// Gaussian NLL of the joints, per value.
    pub joint_nll: f32,
    /// Mean squared error of the mean frames.
    pub image_mse: f32,
    /// Mean squared error of the mean joints.
    pub joint_mse: f32,
    /// KL(posterior ‖ prior) of the latent z per sequence (0 without a latent path).
    pub kl: f32,
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
                (self.kl.clone()).unwrap_or_else(|| self.joint_mse.zeros_like()),
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
            kl: at(5),
        }
    }
}

impl LossValues {
    /// The mean of several batches' values, each part on its own (zero for none): the
    /// validation batches', or a step's shards' when the batch is split between devices.
    pub fn mean(values: &[LossValues]) -> LossValues {
        let mut sum = LossValues {
            total: 0.0,
            image_nll: 0.0,
            joint_nll: 0.0,
            image_mse: 0.0,
            joint_mse: 0.0,
            kl: 0.0,
        };
        for v in values {
            sum.total += v.total;
            sum.image_nll += v.image_nll;
            sum.joint_nll += v.joint_nll;
            sum.image_mse += v.image_mse;
            sum.joint_mse += v.joint_mse;
            sum.kl += v.kl;
        }
        let n = values.len().max(1) as f32;
        LossValues {
            total: sum.total / n,
            image_nll: sum.image_nll / n,
            joint_nll: sum.joint_nll / n,
            image_mse: sum.image_mse / n,
            joint_mse: sum.joint_mse / n,
            kl: sum.kl / n,
        }
    }
}

/// The Gaussian negative log-likelihood of the targets under the prediction, per value:
/// `½·log(2π) + log σ + (x − μ)² / (2σ²)` (burn's `GaussianNLLLoss` with the constant, so the
/// numbers are true negative log-densities in nats), averaged over every value of a
/// modality, then `total = image_nll + joint_weight · joint_nll`.
///
/// With `beta` > 0 the total is β-NLL (Seitzer et al. 2022, "On the Pitfalls of
/// Heteroscedastic Uncertainty Estimation"): each value's NLL weighed by its σ^(2β), held
/// constant. The NLL's gradient on a mean is (μ − x)/σ², so without it the pixels a model is
/// sure of (the still background, σ at the floor) outweigh those it is not (the moving arm) by
/// up to 10⁴, and the mean of what moves is barely learnt; β = 1 gives every mean the squared
/// error's gradient. `image_nll` and `joint_nll` stay the plain NLL (β = 0) either way.
///
/// Shapes: `target_images` `[B, M, 3, S, S]`, `target_joints` `[B, M, 7]`, as the prediction.
pub fn gaussian_loss(
    prediction: &Prediction,
    target_images: Tensor<5>,
    target_joints: Tensor<3>,
    joint_weight: f64,
    beta: f64,
) -> Loss {
    let image = NllParts::new(
        prediction.image_mean.clone(),
        prediction.image_sigma.clone(),
        target_images.clone(),
        beta,
    );
    let joint = NllParts::new(
        prediction.joint_mean.clone(),
        prediction.joint_sigma.clone(),
        target_joints.clone(),
        beta,
    );
    let total = image.weighted + joint.weighted.mul_scalar(joint_weight);
    let (image_nll, joint_nll) = (image.plain, joint.plain);
    let image_mse = (prediction.image_mean.clone().detach() - target_images)
        .square()
        .mean();
    let joint_mse = (prediction.joint_mean.clone().detach() - target_joints)
        .square()
        .mean();
    Loss {
        total,
        image_nll,
        joint_nll,
        image_mse,
        joint_mse,
        kl: None,
    }
}

/// The Gaussian NLL of `target` joints under `mean` and `sigma` (all `[B, M, 7]`), per value,
/// weighed as β-NLL when `beta` > 0 (see [`gaussian_loss`]).
pub fn joint_nll(mean: Tensor<3>, sigma: Tensor<3>, target: Tensor<3>, beta: f64) -> Tensor<1> {
    NllParts::new(mean, sigma, target, beta).weighted
}

/// One modality's NLL per value, plain (detached) and as the objective (β-weighted).
struct NllParts {
    plain: Tensor<1>,
    weighted: Tensor<1>,
}

impl NllParts {
    fn new<const D: usize>(
        mean: Tensor<D>,
        sigma: Tensor<D>,
        target: Tensor<D>,
        beta: f64,
    ) -> NllParts {
        let values = GaussianNLLLossConfig::new()
            .with_full(true)
            .init()
            .forward_no_reduction(mean, target, sigma.clone().square());
        let plain = values.clone().mean();
        let weighted = if beta > 0.0 {
            (values * sigma.detach().powf_scalar(2.0 * beta)).mean()
        } else {
            plain.clone()
        };
        NllParts {
            plain: plain.detach(),
            weighted,
        }
    }
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
        let v = gaussian_loss(&prediction, images, joints, 0.5, 0.0).values();
        let half_log_2pi = 0.5 * (2.0 * std::f32::consts::PI).ln();
        let image = half_log_2pi + 0.1f32.ln() + 0.04 / (2.0 * 0.01);
        let joint = half_log_2pi + 2.0;
        assert!((v.image_nll - image).abs() < 1e-4, "{v:?} vs {image}");
        assert!((v.joint_nll - joint).abs() < 1e-5, "{v:?} vs {joint}");
        assert!((v.total - (image + 0.5 * joint)).abs() < 1e-4);
        assert!((v.image_mse - 0.04).abs() < 1e-6);
        assert!((v.joint_mse - 4.0).abs() < 1e-6);
    }

    // Gradients need the autodiff device, which the wasm build leaves out.
    #[cfg(not(target_arch = "wasm32"))]
    #[test]
    fn beta_nll_weighs_each_value_by_its_variance_and_gives_means_the_squared_error_s_gradient() {
        let device = Device::flex().autodiff();
        let mean = Tensor::<5>::from_floats([[[[[0.5, 0.2]]]]], &device).require_grad();
        let sigma = Tensor::<5>::from_floats([[[[[0.1, 0.5]]]]], &device).require_grad();
        let prediction = Prediction {
            image_mean: mean.clone(),
            image_sigma: sigma.clone(),
            image_drawn: None,
            joint_mean: Tensor::zeros([1, 1, 7], &device),
            joint_sigma: Tensor::full([1, 1, 7], 0.5, &device),
        };
        let images = Tensor::<5>::from_floats([[[[[0.7, 0.7]]]]], &device);
        let joints = Tensor::full([1, 1, 7], 1.0, &device);
        let loss = gaussian_loss(&prediction, images, joints, 0.5, 1.0);
        let v = loss.values();
        let nll = |s: f32, d: f32| {
            0.5 * (2.0 * std::f32::consts::PI).ln() + s.ln() + d * d / (2.0 * s * s)
        };
        let (a, b, j) = (nll(0.1, 0.2), nll(0.5, 0.5), nll(0.5, 1.0));
        // The parts stay the plain NLL; the total weighs each value by σ².
        assert!((v.image_nll - (a + b) / 2.0).abs() < 1e-4, "{v:?}");
        assert!((v.joint_nll - j).abs() < 1e-5, "{v:?}");
        let total = (0.01 * a + 0.25 * b) / 2.0 + 0.5 * 0.25 * j;
        assert!((v.total - total).abs() < 1e-5, "{} vs {total}", v.total);
        // β = 1: ∂/∂μ = (μ − x) / 2 values, whatever σ (the squared error's gradient).
        let grads = loss.total.backward();
        let got: Vec<f32> = mean.grad(&grads).unwrap().into_data().try_to_vec().unwrap();
        for (g, want) in got.iter().zip([-0.1f32, -0.25]) {
            assert!((g - want).abs() < 1e-5, "{got:?}");
        }
    }
}
