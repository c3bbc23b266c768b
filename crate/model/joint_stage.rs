use burn::config::Config;
use burn::module::{Module, Param};
use burn::nn::Linear;
use burn::tensor::activation::{gelu, softplus};
use burn::tensor::{Device, Tensor, TensorData};

use super::joint_stage_inputs::{interpolated, joint_stage_input_len, joint_stage_inputs};
use crate::data::Joints;

/// Hidden layers of the stage's network.
pub const JOINT_STAGE_LAYERS: usize = 3;
/// Lower bound of the stage's σ (radians, and metres of gripper travel).
pub const JOINT_STAGE_SIGMA_FLOOR: f64 = 1e-4;

/// Configuration of a [`JointStage`] stage.
#[derive(Config, Debug)]
pub struct JointStageConfig {
    /// Width of each hidden layer.
    #[config(default = 256)]
    pub width: usize,
    /// Joint values a step (D).
    #[config(default = 7)]
    pub joints: usize,
}

/// The joint stage, a model file's second stage, in joint space: shown only frames (blend 1),
/// the network reads the joints at each glimpse well (about 0.03 rad) but the trajectory
/// between the glimpses it imagines lands pushes short of where the demonstration did. The
/// stage sees the reads side by side ([`joint_stage_inputs`]) and corrects their linear
/// interpolation at each target time (GELU layers, then a mean and a σ head). It learns from
/// the network's own reads of training frames at random glimpse layouts (`train
/// --joint-stage`, [`crate::train::fit_joint_stage`]).
#[derive(Module, Debug)]
pub struct JointStage {
    /// What every input is divided by (the largest magnitude it took in training); not
    /// trained.
    pub scale: Param<Tensor<1>>,
    /// The hidden layers.
    pub layers: Vec<Linear>,
    /// The correction of the interpolated reads (radians); zero in a fresh stage.
    pub mean: Linear,
    /// σ of the corrected joints, through softplus above [`JOINT_STAGE_SIGMA_FLOOR`]; it reads the
    /// hidden layers without training them, so that fitting σ cannot move the mean.
    pub sigma: Linear,
}

impl JointStageConfig {
    /// A stage whose correction is zero: it predicts the interpolated reads.
    pub fn init(&self, device: &Device) -> JointStage {
        let (d, features) = (self.joints, joint_stage_input_len(self.joints));
        let mut inputs = features;
        let layers = (0..JOINT_STAGE_LAYERS)
            .map(|_| {
                let layer = super::init::dense(inputs, self.width, device);
                inputs = self.width;
                layer
            })
            .collect();
        let mut mean = super::init::dense(inputs, d, device);
        mean.weight = Param::from_tensor(Tensor::zeros([inputs, d], device));
        JointStage {
            scale: Param::from_tensor(Tensor::ones([features], device)).set_require_grad(false),
            layers,
            mean,
            sigma: super::init::dense(inputs, d, device),
        }
    }
}

impl JointStage {
    /// Width of the hidden layers.
    pub fn width(&self) -> usize {
        self.mean.weight.dims()[0]
    }

    /// Joint values a step (D).
    pub fn joints(&self) -> usize {
        self.mean.weight.dims()[1]
    }

    /// `[M, joint_stage_input_len(D)]` features and `[M, D]` interpolated reads to the mean
    /// and σ joints, `[M, D]` each, in joint units.
    pub fn forward(&self, x: Tensor<2>, start: Tensor<2>) -> (Tensor<2>, Tensor<2>) {
        let x = x / self.scale.val().unsqueeze::<2>();
        let h = self
            .layers
            .iter()
            .fold(x, |x, layer| gelu(layer.forward(x)));
        let mean = start + self.mean.forward(h.clone());
        let sigma =
            softplus(self.sigma.forward(h.detach()), 1.0).add_scalar(JOINT_STAGE_SIGMA_FLOOR);
        (mean, sigma)
    }

    /// The joints at `targets` (phases) for glimpses at `times` read as `reads`: mean and σ
    /// per target, in radians (and gripper units).
    pub fn predict(
        &self,
        times: &[f32],
        reads: &Joints,
        targets: &[f32],
        device: &Device,
    ) -> (Joints, Joints) {
        let (m, d) = (targets.len(), reads.width());
        let (x, start) = joint_stage_inputs(times, reads, targets);
        let x = Tensor::from_data(TensorData::new(x, [m, joint_stage_input_len(d)]), device);
        let start = Tensor::from_data(TensorData::new(start, [m, d]), device);
        let (mean, sigma) = self.forward(x, start);
        (rows(mean), rows(sigma))
    }

    /// [`JointStage::predict`] for reads a trajectory passes through exactly (a sampled
    /// future's observations and drawn steps): the stage's correction at each glimpse,
    /// interpolated, is taken off, so that it shapes the path between the glimpses and
    /// moves none of them (its correction is meant for reads of frames, not for draws).
    pub fn predict_through(
        &self,
        times: &[f32],
        reads: &Joints,
        targets: &[f32],
        device: &Device,
    ) -> (Joints, Joints) {
        let (mut mean, sigma) = self.predict(times, reads, targets, device);
        let (mut corrections, _) = self.predict(times, reads, times, device);
        for (k, read) in reads.rows().enumerate() {
            (corrections.row_mut(k).iter_mut().zip(read)).for_each(|(c, r)| *c -= r);
        }
        let taken = interpolated(times, &corrections, targets);
        for (k, c) in taken.iter().enumerate() {
            mean.row_mut(k).iter_mut().zip(c).for_each(|(m, c)| *m -= c);
        }
        (mean, sigma)
    }
}

fn rows(t: Tensor<2>) -> Joints {
    let d = t.dims()[1];
    Joints::new(d, super::values(t)).expect("rows of D values")
}
