use burn::module::Module;
use burn::optim::{GradientsAccumulator, GradientsParams};
use burn::tensor::{Device, Distribution, Tensor};

use crate::augment::{Batch, JointTargets};
use crate::model::{
    joint_nll, joint_target_tensors, kl_divergence, tensors, BatchTensors, LossValues, Model,
    Representation,
};

use super::{TrainConfig, TrainError};

/// A step's loss values and gradient on `batch` (and its joint-only targets), with the batch
/// split evenly between `devices` by sequence (data parallelism; one device: the batch
/// whole). Each device takes a shard with a replica of `model` (on a thread of its own, so
/// GPUs work at once) and backpropagates its loss divided by the number of shards: every
/// term of the objective is a mean, so those gradients sum to the whole batch's. The sum is
/// made on the first device, where `model` lives and the optimiser steps; the values are the
/// shards' mean, the batch's. Burn's collective all-reduce is not used: the CPU backend has
/// none, and the sum is the same on every backend.
///
/// `devices` must not be empty and their number must divide `batch.batch`
/// ([`TrainDevices::check_batch`](super::TrainDevices::check_batch)). A non-finite loss
/// gives no gradient: the caller stops before touching the weights.
pub(super) fn gradients(
    model: &Model,
    batch: &Batch,
    joint_targets: &JointTargets,
    config: &TrainConfig,
    devices: &[Device],
) -> Result<(LossValues, GradientsParams), TrainError> {
    let [main, others @ ..] = devices else {
        return Err(TrainError::config("devices", "no device to train on"));
    };
    let n = devices.len();
    if others.is_empty() {
        return shard(model, batch, joint_targets, config, main, n);
    }
    let (batches, joints) = (batch.shards(n), joint_targets.shards(n));
    let shards = std::thread::scope(|scope| {
        let replicas: Vec<_> = others
            .iter()
            .zip(batches.iter().zip(&joints).skip(1))
            .map(|(device, (batch, joints))| {
                let replica = model.clone();
                scope.spawn(move || {
                    let replica = replica.fork(device);
                    shard(&replica, batch, joints, config, device, n)
                        .map(|(values, grads)| (values, grads.to_device(main, &replica)))
                })
            })
            .collect();
        let first = shard(model, &batches[0], &joints[0], config, main, n);
        let rest = replicas.into_iter().map(|replica| {
            replica
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        });
        std::iter::once(first)
            .chain(rest)
            .collect::<Result<Vec<_>, _>>()
    })?;
    let mut sum = GradientsAccumulator::<Model>::new();
    let mut values = Vec::with_capacity(n);
    for (v, grads) in shards {
        sum.accumulate(model, grads);
        values.push(v);
    }
    Ok((LossValues::mean(&values), sum.grads()))
}

/// The objective on one shard of `shards` (the model's loss, plus the drawn frame's squared
/// error and the joint-only targets' NLL as configured): its values, and the gradient of its
/// total divided by `shards` (none when the total is not finite).
fn shard(
    model: &Model,
    batch: &Batch,
    joint_targets: &JointTargets,
    config: &TrainConfig,
    device: &Device,
    shards: usize,
) -> Result<(LossValues, GradientsParams), TrainError> {
    let batch = tensors(batch, device)?;
    let joint_only = (joint_targets.targets > 0)
        .then(|| joint_target_tensors(joint_targets, model.joint_count(), device))
        .transpose()?;
    let representation = model.encode(&batch)?;
    let (representation, kl) = posterior_draw(model, representation, &batch, &joint_only, device)?;
    let prediction = model.decode(&representation, batch.target_times.clone())?;
    let mut loss = model.loss(&prediction, &batch, config.beta_nll)?;
    if let (Some(drawn), Some(frames)) = (&prediction.image_drawn, &batch.target_images) {
        if config.drawn_frame_weight > 0.0 {
            let mse = (drawn.clone() - frames.clone()).square().mean();
            loss.total = loss.total + mse.mul_scalar(config.drawn_frame_weight);
        }
    }
    if let Some((times, joints)) = joint_only {
        let (mean, sigma) = model.decode_joints(&representation, times)?;
        let nll = joint_nll(mean, sigma, joints, config.beta_nll);
        loss.total = loss.total + nll.mul_scalar(config.model.joint_weight);
    }
    if let Some(kl) = kl {
        loss.kl = Some(kl.clone().detach());
        let penalised = kl.clamp_min(config.latent_free_nats);
        loss.total = loss.total + penalised.mul_scalar(config.latent_kl);
    }
    let values = loss.values();
    if !values.total.is_finite() {
        return Ok((values, GradientsParams::new()));
    }
    // Exact for one shard (x / 1 = x): a single device's step is the undivided one.
    let total = loss.total.div_scalar(shards as f64);
    Ok((values, GradientsParams::from_grads(total.backward(), model)))
}

/// For a model with a latent path: the representation with z drawn from its posterior given
/// the targets' joints, those with frames and the joint-only ones (reparameterised), and
/// KL(posterior ‖ prior). Other models: the representation as it is, no KL.
fn posterior_draw(
    model: &Model,
    representation: Representation,
    batch: &BatchTensors,
    joint_only: &Option<(Tensor<2>, Tensor<3>)>,
    device: &Device,
) -> Result<(Representation, Option<Tensor<1>>), TrainError> {
    if model.latent_size().is_none() {
        return Ok((representation, None));
    }
    let joints = (batch.target_joints.clone())
        .ok_or_else(|| TrainError::config("latent", "the batch has no target joints"))?;
    let (mut times, mut joints) = (vec![batch.target_times.clone()], vec![joints]);
    if let Some((t, j)) = joint_only {
        times.push(t.clone());
        joints.push(j.clone());
    }
    let posterior = model.posterior(
        &representation,
        Tensor::cat(times, 1),
        Tensor::cat(joints, 1),
    );
    let (Some(q), Some(p)) = (posterior, model.prior(&representation)) else {
        return Ok((representation, None));
    };
    let noise = Tensor::random(q.mean.dims(), Distribution::Normal(0.0, 1.0), device);
    let drawn = model.with_latent(&representation, q.draw(noise))?;
    Ok((drawn, Some(kl_divergence(&q, &p))))
}

#[cfg(test)]
mod tests {
    use burn::module::{ModuleVisitor, Param};
    use burn::tensor::Tensor;

    use super::*;
    use crate::data::JOINTS;
    use crate::model::{ModelConfig, ModelKind};

    /// Four sequences of made-up values, 1 to 3 real contexts each, two targets and two
    /// joint-only targets.
    fn batch(s: usize) -> (Batch, JointTargets) {
        let mut x = 0.37f32;
        let mut next = move || {
            x = (x * 9.7 + 0.13).fract();
            x
        };
        let mut batch = Batch::with_targets(4, 3, 2, s, JOINTS);
        for values in [
            &mut batch.context_images,
            &mut batch.context_joints,
            &mut batch.context_times,
            &mut batch.target_images,
            &mut batch.target_joints,
            &mut batch.target_times,
            &mut batch.blend,
        ] {
            values.iter_mut().for_each(|v| *v = next());
        }
        for (i, mask) in batch.context_mask.iter_mut().enumerate() {
            *mask = if i % 3 <= (i / 3) % 3 { 1.0 } else { 0.0 };
        }
        let joints = JointTargets {
            batch: 4,
            targets: 2,
            times: (0..8).map(|_| next()).collect(),
            joints: (0..8 * 7).map(|_| next()).collect(),
        };
        (batch, joints)
    }

    /// The largest difference between two gradients of a parameter against the largest value
    /// of the first, over all parameters.
    struct Compare<'a> {
        want: &'a GradientsParams,
        got: &'a GradientsParams,
        worst: f32,
        params: usize,
    }

    impl ModuleVisitor for Compare<'_> {
        fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
            let (Some(want), Some(got)) =
                (self.want.get::<D>(param.id), self.got.get::<D>(param.id))
            else {
                panic!("parameter {} has no gradient", param.id);
            };
            let scale: f32 = want.clone().abs().max().into_scalar();
            let diff: f32 = (want - got).abs().max().into_scalar();
            self.worst = self.worst.max(diff / scale.max(1e-12));
            self.params += 1;
        }
    }

    #[test]
    fn the_shards_gradients_sum_to_the_whole_batch_s() {
        let device = Device::flex().autodiff();
        let mut config = TrainConfig::new(ModelConfig::new(ModelKind::Pte), 1, 1);
        config.joint_targets = 2;
        let model = config.model.init(&device).unwrap();
        let (batch, joints) = batch(config.model.image_size);
        let (whole, want) = gradients(
            &model,
            &batch,
            &joints,
            &config,
            std::slice::from_ref(&device),
        )
        .unwrap();
        for n in [2, 4] {
            let (split, got) =
                gradients(&model, &batch, &joints, &config, &vec![device.clone(); n]).unwrap();
            assert!(
                (split.total - whole.total).abs() <= 1e-5 * whole.total.abs().max(1.0),
                "{n} shards: loss {} against {}",
                split.total,
                whole.total
            );
            let mut compare = Compare {
                want: &want,
                got: &got,
                worst: 0.0,
                params: 0,
            };
            model.visit(&mut compare);
            assert!(compare.params > 10, "{} parameters", compare.params);
            assert!(
                compare.worst <= 1e-4,
                "{n} shards: gradients differ by {} of their scale",
                compare.worst
            );
        }
    }
}
