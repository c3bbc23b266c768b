use std::path::Path;

use burn::tensor::Device;
use rand::SeedableRng;
use rand_pcg::Pcg64;

use super::{
    fit_joint_stage, JointStageExamples, JointStageFit, JointStageFitProgress, TrainError,
};
use crate::data::{read_sequence_from, write_atomic, Disk, SequenceRef};
use crate::model::{self, with_joint_sigma_scale};
use crate::predict::Predictor;

/// What [`add_joint_stage`] reports as it goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointStageProgress {
    /// `done` of `total` sequences read by the network at their glimpse layouts.
    Reading { done: usize, total: usize },
    /// The stage's fit.
    Fitting(JointStageFitProgress),
}

/// Fits a joint stage ([`crate::model::JointStage`]) to the model file at `path` and rewrites
/// it (atomically) with the stage, keeping its network, normalisation and σ scales: the
/// network reads the joints from `fit.draws` glimpse layouts of each `train` sequence (frames
/// only) and of each `held_out` one, the stage's mean learns from the first and its σ from
/// the second (from the first too when `held_out` is empty).
pub fn add_joint_stage(
    path: &Path,
    train: &[SequenceRef],
    held_out: &[SequenceRef],
    camera: Option<&str>,
    fit: JointStageFit,
    device: &Device,
    mut on_progress: impl FnMut(JointStageProgress),
) -> Result<(), TrainError> {
    fit.validate()?;
    let bytes = std::fs::read(path).map_err(TrainError::io(path))?;
    let predictor = Predictor::from_bytes(&bytes).map_err(model::ModelError::in_file(path))?;
    let size = predictor.model().image_size() as u32;
    let mut rng = Pcg64::seed_from_u64(fit.seed);
    let total = train.len() + held_out.len();
    let d = predictor.joint_count();
    let mut sets = [JointStageExamples::new(d), JointStageExamples::new(d)];
    for (done, (set, r)) in [0, 1]
        .into_iter()
        .flat_map(|s| [train, held_out][s].iter().map(move |r| (s, r)))
        .enumerate()
    {
        let seq = read_sequence_from(&Disk, &r.dir, r.id, camera, Some(size))?;
        crate::data::Dataset::check_width(r, seq.joints.width(), d, &path.display().to_string())?;
        sets[set].add(&predictor, &seq, fit.draws, &mut rng)?;
        on_progress(JointStageProgress::Reading {
            done: done + 1,
            total,
        });
    }
    let [train, held_out] = &sets;
    let held_out = (held_out.rows() > 0).then_some(held_out);
    let stage = fit_joint_stage(train, held_out, fit, device, |p| {
        on_progress(JointStageProgress::Fitting(p))
    })?;
    let (network, header) = model::load_with_header(&bytes, &Device::flex(), None, None)?;
    let model = network.with_joint_stage(stage);
    let half = header.weights.dtype == model::WeightDType::F16;
    let out = model::save_bytes(&model, &header.normalization, half)?;
    let out = match header.joint_sigma_scale {
        Some(_) => with_joint_sigma_scale(&out, header.joint_sigma_scales())?,
        None => out,
    };
    write_atomic(path, &out)?;
    Ok(())
}
