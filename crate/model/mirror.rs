use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::Linear;
use burn::tensor::activation::{gelu, softplus};
use burn::tensor::{Device, Tensor, TensorData};

use super::mirror_inputs::{mirror_inputs, MIRROR_INPUTS};
use crate::data::JOINTS;

/// Hidden layers of the stage's network.
pub const MIRROR_LAYERS: usize = 3;
/// Lower bound of the stage's σ (radians, and metres of gripper travel).
pub const MIRROR_SIGMA_FLOOR: f64 = 1e-4;

/// Configuration of a [`Mirror`] stage.
#[derive(Config, Debug)]
pub struct MirrorConfig {
    /// Width of each hidden layer.
    #[config(default = 256)]
    pub width: usize,
}

/// The mirror's second stage, in joint space: shown only frames (blend 1), the network reads
/// the joints at each glimpse well (about 0.03 rad) but the trajectory between the glimpses
/// it imagines lands pushes short of where the demonstration did. The stage sees the reads
/// side by side ([`mirror_inputs`]) and corrects their linear interpolation at each target
/// time (GELU layers, then a mean and a σ head). It learns from the network's own reads of
/// training frames at random glimpse layouts (`train --mirror`, [`crate::train::fit_mirror`]).
#[derive(Module, Debug)]
pub struct Mirror {
    /// What every input is divided by (the largest magnitude it took in training); not
    /// trained.
    pub scale: Param<Tensor<1>>,
    /// The hidden layers.
    pub layers: Vec<Linear>,
    /// The correction of the interpolated reads (radians); zero in a fresh stage.
    pub mean: Linear,
    /// σ of the corrected joints, through softplus above [`MIRROR_SIGMA_FLOOR`]; it reads the
    /// hidden layers without training them, so that fitting σ cannot move the mean.
    pub sigma: Linear,
}

impl MirrorConfig {
    /// A stage whose correction is zero: it predicts the interpolated reads.
    pub fn init(&self, device: &Device) -> Mirror {
        let mut inputs = MIRROR_INPUTS;
        let layers = (0..MIRROR_LAYERS)
            .map(|_| {
                let layer = super::init::dense(inputs, self.width, device);
                inputs = self.width;
                layer
            })
            .collect();
        let mut mean = super::init::dense(inputs, JOINTS, device);
        mean.weight = Param::from_tensor(Tensor::zeros([inputs, JOINTS], device));
        Mirror {
            scale: Param::from_tensor(Tensor::ones([MIRROR_INPUTS], device))
                .set_require_grad(false),
            layers,
            mean,
            sigma: super::init::dense(inputs, JOINTS, device),
        }
    }
}

impl Mirror {
    /// Width of the hidden layers.
    pub fn width(&self) -> usize {
        self.mean.weight.dims()[0]
    }

    /// `[M, MIRROR_INPUTS]` features and `[M, 7]` interpolated reads to the mean and σ joints,
    /// `[M, 7]` each, in radians (and gripper units).
    pub fn forward(&self, x: Tensor<2>, start: Tensor<2>) -> (Tensor<2>, Tensor<2>) {
        let x = x / self.scale.val().unsqueeze::<2>();
        let h = self
            .layers
            .iter()
            .fold(x, |x, layer| gelu(layer.forward(x)));
        let mean = start + self.mean.forward(h.clone());
        let sigma = softplus(self.sigma.forward(h.detach()), 1.0).add_scalar(MIRROR_SIGMA_FLOOR);
        (mean, sigma)
    }

    /// The joints at `targets` (phases) for glimpses at `times` read as `reads`: mean and σ
    /// per target, in radians (and gripper units).
    pub fn predict(
        &self,
        times: &[f32],
        reads: &[[f32; JOINTS]],
        targets: &[f32],
        device: &Device,
    ) -> (Vec<[f32; JOINTS]>, Vec<[f32; JOINTS]>) {
        let m = targets.len();
        let (x, start) = mirror_inputs(times, reads, targets);
        let x = Tensor::from_data(TensorData::new(x, [m, MIRROR_INPUTS]), device);
        let start = Tensor::from_data(TensorData::new(start, [m, JOINTS]), device);
        let (mean, sigma) = self.forward(x, start);
        (rows(mean), rows(sigma))
    }
}

fn rows(t: Tensor<2>) -> Vec<[f32; JOINTS]> {
    super::values(t)
        .chunks_exact(JOINTS)
        .map(|r| std::array::from_fn(|j| r[j]))
        .collect()
}
