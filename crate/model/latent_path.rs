use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::Linear;
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Tensor};

use super::aggregation::masked_mean;

/// Configuration of a [`LatentPath`].
#[derive(Config, Debug)]
pub struct LatentPathConfig {
    /// Size of the context encodings it reads (H), and of what it adds to the decoder input.
    pub hidden: usize,
    /// L: size of the global latent z.
    pub latent: usize,
}

/// The latent path of a neural process (Garnelo et al. 2018, "Neural Processes"; the paper's
/// future work, "Latent Path"): one global latent z per sequence, Gaussian, from its
/// points' encodings, whose projection is added to the decoder input at every target. What the
/// contexts leave open (how far a push goes) is drawn once per future, so every step of it
/// agrees. Trained with its posterior q(z | contexts and targets) against its prior p(z |
/// contexts) (the KL term, [`kl_divergence`]); predictions take z at the prior's mean,
/// sampled futures draw it ([`crate::futures`]).
#[derive(Module, Debug)]
pub struct LatentPath {
    /// Per point, H → H (ReLU), before the set mean.
    pub point: Linear,
    /// The mean's H → 2L: the mean and the raw σ of z.
    pub statistics: Linear,
    /// L → H, added to the decoder input; zero in a fresh path, so a trained network given
    /// one predicts as before and learns to use z.
    pub projection: Linear,
}

/// A diagonal Gaussian over z, `[B, L]` mean and σ.
#[derive(Debug, Clone)]
pub struct LatentGaussian {
    /// `[B, L]`.
    pub mean: Tensor<2>,
    /// `[B, L]`, in (0.1, 1): bounded below as in the neural process family, so that the KL
    /// stays finite and the prior never collapses to a point.
    pub sigma: Tensor<2>,
}

/// The least σ of z.
const SIGMA_MIN: f64 = 0.1;

impl LatentPathConfig {
    /// Builds the path; its projection starts at zero.
    pub fn init(&self, device: &Device) -> LatentPath {
        let mut projection = super::init::dense(self.latent, self.hidden, device);
        projection.weight = Param::from_tensor(Tensor::zeros([self.latent, self.hidden], device));
        LatentPath {
            point: super::init::dense(self.hidden, self.hidden, device),
            statistics: super::init::dense(self.hidden, 2 * self.latent, device),
            projection,
        }
    }
}

impl LatentPath {
    /// L.
    pub fn latent(&self) -> usize {
        self.projection.weight.dims()[0]
    }

    /// The Gaussian over z of `[B, N, H]` point encodings with a `[B, N]` 0/1 mask (padding 0).
    pub fn distribution(&self, points: Tensor<3>, mask: Tensor<2>) -> LatentGaussian {
        let pooled = masked_mean(relu(self.point.forward(points)), mask);
        let stats = self.statistics.forward(pooled);
        let [b, two_l] = stats.dims();
        let l = two_l / 2;
        LatentGaussian {
            mean: stats.clone().slice([0..b, 0..l]),
            sigma: sigmoid(stats.slice([0..b, l..two_l]))
                .mul_scalar(1.0 - SIGMA_MIN)
                .add_scalar(SIGMA_MIN),
        }
    }

    /// What `[B, L]` latents add to the decoder input, `[B, H]`.
    pub fn project(&self, z: Tensor<2>) -> Tensor<2> {
        self.projection.forward(z)
    }
}

impl LatentGaussian {
    /// `[B, L]` draws mean + σ·ε from standard normal `[B, L]` noise ε (reparameterised: the
    /// gradient reaches the mean and σ).
    pub fn draw(&self, noise: Tensor<2>) -> Tensor<2> {
        self.mean.clone() + self.sigma.clone() * noise
    }
}

/// KL(q ‖ p) of two diagonal Gaussians, summed over z's L values, averaged over the batch:
/// log(σp/σq) + (σq² + (μq − μp)²) / (2σp²) − ½ per value.
pub fn kl_divergence(q: &LatentGaussian, p: &LatentGaussian) -> Tensor<1> {
    let [b, _] = q.mean.dims();
    let var_p = p.sigma.clone().square();
    let per_value = (p.sigma.clone().log() - q.sigma.clone().log())
        + (q.sigma.clone().square() + (q.mean.clone() - p.mean.clone()).square())
            / var_p.mul_scalar(2.0)
        - 0.5;
    per_value.sum().div_scalar(b as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian(mean: [[f32; 2]; 1], sigma: [[f32; 2]; 1]) -> LatentGaussian {
        let device = Device::flex();
        LatentGaussian {
            mean: Tensor::from_floats(mean, &device),
            sigma: Tensor::from_floats(sigma, &device),
        }
    }

    #[test]
    fn kl_is_zero_for_equal_gaussians_and_matches_the_formula() {
        let p = gaussian([[0.0, 1.0]], [[1.0, 0.5]]);
        let same: f32 = kl_divergence(&p, &p).into_scalar();
        assert!(same.abs() < 1e-6, "{same}");
        let q = gaussian([[1.0, 1.0]], [[0.5, 0.5]]);
        // First value: ln 2 + (0.25 + 1) / 2 − ½; the second equal.
        let want = 2f32.ln() + 1.25 / 2.0 - 0.5;
        let got: f32 = kl_divergence(&q, &p).into_scalar();
        assert!((got - want).abs() < 1e-5, "{got} against {want}");
    }

    #[test]
    fn a_fresh_path_adds_nothing_and_its_sigma_is_bounded() {
        let device = Device::flex();
        let path = LatentPathConfig::new(8, 3).init(&device);
        let points = Tensor::<3>::ones([2, 4, 8], &device).mul_scalar(50.0);
        let mask = Tensor::<2>::ones([2, 4], &device);
        let z = path.distribution(points, mask);
        let sigma: Vec<f32> = z.sigma.clone().into_data().try_to_vec().unwrap();
        assert!(sigma.iter().all(|s| (0.1..=1.0).contains(s)), "{sigma:?}");
        let added: Vec<f32> = path.project(z.mean).into_data().try_to_vec().unwrap();
        assert!(added.iter().all(|v| *v == 0.0), "{added:?}");
        assert_eq!(path.latent(), 3);
    }
}
