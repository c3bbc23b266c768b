use burn::module::Param;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::{Device, Tensor, TensorData};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::{MirrorExamples, Schedule, TrainError};
use crate::model::{Mirror, MirrorConfig};

/// How `train --mirror` fits the [`Mirror`] stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorFit {
    /// Width of the stage's hidden layers.
    pub width: usize,
    /// Glimpse layouts the network reads per sequence ([`crate::train::layout`]).
    pub draws: usize,
    /// Adam steps (learning rate `lr`, cosine schedule to 0).
    pub steps: u64,
    /// Examples per step.
    pub batch: usize,
    /// Peak learning rate.
    pub lr: f64,
    /// Seeds the weights and the batches.
    pub seed: u64,
}

impl Default for MirrorFit {
    fn default() -> Self {
        MirrorFit {
            width: 256,
            draws: 9,
            steps: 20_000,
            batch: 512,
            lr: 1e-3,
            seed: 0,
        }
    }
}

impl MirrorFit {
    /// Fails on a setting that leaves nothing to fit: no layout read, no width, no batch.
    pub fn validate(&self) -> Result<(), TrainError> {
        if self.draws == 0 {
            return Err(TrainError::config(
                "mirror_draws",
                "is 0: expected at least one glimpse layout per sequence",
            ));
        }
        if self.width == 0 || self.batch == 0 {
            return Err(TrainError::config(
                "mirror",
                "the stage's width and batch must be at least 1",
            ));
        }
        Ok(())
    }
}

/// One report of [`fit_mirror`]'s progress: the step, and the batch's joint RMSE (all seven
/// columns, radians) on the training reads and on the held-out ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorProgress {
    pub step: u64,
    pub rmse: f64,
    pub held_out_rmse: f64,
}

/// Fits a mirror stage on `device` (an autodiff device): its mean by the squared error on
/// `train`, its σ by the Gaussian NLL on `held_out` (reads of sequences the network did not
/// train on, whose errors are the ones a user meets; `train` itself when none is given), the
/// mean held fixed there. Calls `on_progress` every 500 steps and at the end.
pub fn fit_mirror(
    train: &MirrorExamples,
    held_out: Option<&MirrorExamples>,
    fit: MirrorFit,
    device: &Device,
    mut on_progress: impl FnMut(MirrorProgress),
) -> Result<Mirror, TrainError> {
    fit.validate()?;
    let held_out = held_out.unwrap_or(train);
    for (name, examples) in [("training", train), ("held-out", held_out)] {
        if examples.rows() == 0 {
            return Err(TrainError::config(
                "mirror",
                format!("no {name} examples to fit the mirror stage on"),
            ));
        }
    }
    device.seed(fit.seed);
    let mut mirror = MirrorConfig::new()
        .with_width(fit.width)
        .with_joints(train.joints)
        .init(device);
    mirror.scale = Param::from_tensor(Tensor::from_data(
        TensorData::new(input_scale(train), [train.features()]),
        device,
    ))
    .set_require_grad(false);
    let mut optim = AdamConfig::new().init();
    let mut rng = Pcg64::seed_from_u64(fit.seed);
    for step in 1..=fit.steps {
        let (x, start, truth) = batch(train, fit.batch, &mut rng, device);
        let (mean, _) = mirror.forward(x, start);
        let se = (mean - truth).square().mean();
        let (x, start, truth) = batch(held_out, fit.batch, &mut rng, device);
        let (mean, sigma) = mirror.forward(x, start);
        let held_out_se = (mean.detach() - truth).square();
        let nll = (sigma.clone().log() + held_out_se.clone() / (sigma.square() * 2.0)).mean();
        let (rmse, held_out_rmse) = (scalar(se.clone()).sqrt(), scalar(held_out_se.mean()).sqrt());
        if !(rmse.is_finite() && held_out_rmse.is_finite()) {
            return Err(TrainError::NonFinite {
                step,
                value: rmse as f32,
            });
        }
        let grads = GradientsParams::from_grads((se + nll).backward(), &mirror);
        let lr = Schedule::Cosine {
            final_fraction: 0.0,
        }
        .rate(fit.lr, step - 1, fit.steps);
        mirror = optim.step(lr, mirror, grads);
        if step % 500 == 0 || step == fit.steps {
            on_progress(MirrorProgress {
                step,
                rmse,
                held_out_rmse,
            });
        }
    }
    Ok(mirror)
}

/// The largest magnitude of every input over `examples` (at least 1e-3): what the stage
/// divides its inputs by.
fn input_scale(examples: &MirrorExamples) -> Vec<f32> {
    let mut scale = vec![1e-3f32; examples.features()];
    for row in examples.x.chunks_exact(examples.features()) {
        for (s, v) in scale.iter_mut().zip(row) {
            *s = s.max(v.abs());
        }
    }
    scale
}

/// `size` examples drawn at random: inputs, interpolated reads and truth as tensors.
fn batch(
    examples: &MirrorExamples,
    size: usize,
    rng: &mut Pcg64,
    device: &Device,
) -> (Tensor<2>, Tensor<2>, Tensor<2>) {
    let (rows, f, d) = (examples.rows(), examples.features(), examples.joints);
    let (mut x, mut start, mut truth) = (
        Vec::with_capacity(size * f),
        Vec::with_capacity(size * d),
        Vec::with_capacity(size * d),
    );
    for _ in 0..size {
        let i = rng.random_range(0..rows);
        x.extend_from_slice(&examples.x[i * f..(i + 1) * f]);
        start.extend_from_slice(&examples.start[i * d..(i + 1) * d]);
        truth.extend_from_slice(&examples.truth[i * d..(i + 1) * d]);
    }
    let tensor =
        |v: Vec<f32>, width: usize| Tensor::from_data(TensorData::new(v, [size, width]), device);
    (tensor(x, f), tensor(start, d), tensor(truth, d))
}

fn scalar(t: Tensor<1>) -> f64 {
    crate::model::values(t)[0] as f64
}
