use std::path::{Path, PathBuf};
use std::time::Instant;

use burn::optim::grad_clipping::GradientClippingConfig;
use burn::optim::{AdamConfig, ModuleOptimizer};
use burn::tensor::{Bytes, Device};
use rand::SeedableRng;
use rand_pcg::Pcg64;

use crate::augment::{Batch, Sampler, SamplerConfig};
use crate::data::{write_atomic, Sequence};
use crate::model::{self, glorot, tensors, Initialization, LossValues, Model, Normalization};
use crate::predict::Predictor;

use super::data_parallel::gradients;
use super::{
    BatchStream, Checkpoint, CheckpointState, Metrics, MetricsLog, SequenceStore, Split,
    TrainConfig, TrainDevice, TrainDevices, TrainError, ValQuality,
};

/// Separate random streams: validation batches never shift the training stream.
const VAL_STREAM: u64 = 0x5851_F42D_4C95_7F2D;

/// What the progress display shows after each step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    pub step: u64,
    pub steps: u64,
    pub loss: f32,
    pub val_loss: Option<f32>,
    pub steps_per_s: f64,
}

/// A training run: model, Adam, data and its random stream, checkpoints and metrics in `out`.
pub struct Trainer {
    config: TrainConfig,
    out: PathBuf,
    model: Model,
    optim: ModuleOptimizer,
    /// The training stream's state after the batches of the steps taken: what a checkpoint
    /// records.
    rng: Pcg64,
    step: u64,
    /// The next training batches, read ahead from `rng`'s state.
    batches: BatchStream,
    /// Held-out ids (empty: validation measures training sequences).
    val_ids: Vec<u32>,
    normalization: Normalization,
    val_set: Vec<Batch>,
    /// The held-out sequences the quality benchmark scores, read whole once.
    quality_set: Vec<Sequence>,
    log: MetricsLog,
    best_val: Option<(u64, f32)>,
    /// Best [`ValQuality::score`] so far and its step: the model in `out/best.dmbn`.
    best_quality: Option<(u64, f32)>,
    /// The dataset root, recorded in checkpoints.
    data: Option<PathBuf>,
    /// Where the model lives: the first of `devices`.
    device: Device,
    /// The devices each step's batch is split between.
    devices: Vec<Device>,
}

impl Trainer {
    /// A fresh run on the dataset at `data`, writing into `out` (which must hold no checkpoint:
    /// continue such a run with [`Trainer::resume`]), on the CPU.
    pub fn new(data: &Path, out: &Path, config: TrainConfig) -> Result<Trainer, TrainError> {
        Self::new_on(&TrainDevice::Cpu.into(), data, out, config)
    }

    /// [`Trainer::new`] on `devices` (several: each step's batch split between them).
    pub fn new_on(
        devices: &TrainDevices,
        data: &Path,
        out: &Path,
        config: TrainConfig,
    ) -> Result<Trainer, TrainError> {
        config.validate()?;
        devices.check_batch(config.batch)?;
        let devices = devices.devices()?;
        let device = devices[0].clone();
        if Checkpoint::read(out).is_ok() {
            return Err(TrainError::config(
                "out",
                format!("{} already holds a checkpoint: pass --resume to continue it, or choose another --out", out.display()),
            ));
        }
        std::fs::create_dir_all(out).map_err(TrainError::io(out))?;
        let split = Split::open_camera(data, config.val_fraction, config.camera.as_deref())?;
        // The joint count comes from the data, and so do the names where it has them.
        let mut config = config;
        let (width, names) = split.joints.clone();
        if config.init.is_none() {
            config.model.joints = Some(width);
            config.model.joint_names = names;
        }
        let train = open_store(&split.train, &config, &split)?;
        device.seed(config.seed);
        let model = match &config.init {
            Some(path) => {
                let bytes = std::fs::read(path).map_err(TrainError::io(path))?;
                let model = model::load_bytes_expecting(
                    &bytes,
                    &device,
                    Some(config.model.kind),
                    Some(config.model.image_size),
                )
                .map_err(|e| TrainError::config("init", format!("{}: {e}", path.display())))?
                .0
                // A joint stage learnt the file's network's reads: training leaves it behind
                // (`--joint-stage` fits one to the result).
                .without_joint_stage();
                if model.joint_count() != width {
                    return Err(TrainError::config(
                        "init",
                        format!(
                            "{}: the model has {} joint values a step, the data at {} has {width}: start from a model of this robot",
                            path.display(),
                            model.joint_count(),
                            data.display()
                        ),
                    ));
                }
                config.model.joints = Some(width);
                config.model.joint_names = model.config().joint_names.clone();
                // A read-out of joints from frames, or a latent path, asked for, which the
                // file may lack.
                let model = if config.model.frame_joints == Some(true) {
                    model.reading_frame_joints(&device)?
                } else {
                    model
                };
                match config.model.latent {
                    Some(latent) => model.with_latent_path(latent, &device)?,
                    None => model,
                }
            }
            None => {
                let model = config.model.init(&device)?;
                model.draw_weights();
                match config.initialization {
                    Initialization::He => model,
                    Initialization::Glorot => glorot(model),
                }
            }
        };
        // Fitted on the training data even when starting from a file: the same as the file's
        // for a run on that file's data, and right for other data (the original DMBN data's
        // joints lie radians away from the simulator's: the file's statistics would feed the
        // network values hundreds of σ off).
        let normalization = Normalization::fit(config.model.joint_count(), train.joints())
            .scaled(config.joint_scale);
        let optim = optimizer(&config);
        let state = CheckpointState {
            step: 0,
            rng: Pcg64::seed_from_u64(config.seed),
            config,
            normalization,
            best_val: None,
            best_quality: None,
            data: Some(std::path::absolute(data).unwrap_or_else(|_| data.to_path_buf())),
        };
        Self::assemble(state, out, model, optim, split, train, devices)
    }

    /// Continue the run in `out` from its last checkpoint, with the same settings, on `data`
    /// or (none given) the dataset the checkpoint names; `steps` may extend the run. On the
    /// CPU.
    pub fn resume(
        data: Option<&Path>,
        out: &Path,
        steps: Option<u64>,
    ) -> Result<Trainer, TrainError> {
        Self::resume_on(&TrainDevice::Cpu.into(), data, out, steps)
    }

    /// [`Trainer::resume`] on `devices` (a run may move between devices, and change their
    /// number, at a checkpoint).
    pub fn resume_on(
        devices: &TrainDevices,
        data: Option<&Path>,
        out: &Path,
        steps: Option<u64>,
    ) -> Result<Trainer, TrainError> {
        let (model_bytes, optim_bytes, mut state) = Checkpoint::read(out)?;
        if let Some(steps) = steps {
            state.config.steps = steps;
        }
        state.config.validate()?;
        devices.check_batch(state.config.batch)?;
        let devices = devices.devices()?;
        let device = devices[0].clone();
        let data = match data {
            Some(data) => data.to_path_buf(),
            None => state.data.clone().ok_or_else(|| {
                TrainError::config(
                    "data",
                    format!(
                        "missing: the checkpoint in {} does not name its dataset (written before checkpoints did): pass --data",
                        out.display()
                    ),
                )
            })?,
        };
        let split = Split::open_camera(
            &data,
            state.config.val_fraction,
            state.config.camera.as_deref(),
        )?;
        state.data = Some(data);
        let (model, _, _) = model::load_bytes(&model_bytes, &device)?;
        let optim = optimizer(&state.config)
            .from_bytes(Bytes::from_bytes_vec(optim_bytes))
            .map_err(|e| TrainError::Checkpoint {
                path: Checkpoint::dir(out),
                message: format!("optimizer.bpk: {e:?}"),
            })?;
        let train = open_store(&split.train, &state.config, &split)?;
        Self::assemble(state, out, model, optim, split, train, devices)
    }

    /// A trainer from where a run stands (a fresh run's state at step 0, or a checkpoint's):
    /// the training batches stream from disk on a worker thread; the validation batches and
    /// the quality benchmark's sequences (a fixed number, whatever the dataset's size) are
    /// read once.
    fn assemble(
        state: CheckpointState,
        out: &Path,
        model: Model,
        optim: ModuleOptimizer,
        split: Split,
        mut train: SequenceStore,
        devices: Vec<Device>,
    ) -> Result<Trainer, TrainError> {
        let log = MetricsLog::open(&out.join("metrics.jsonl"), Some(state.step))?;
        let CheckpointState {
            step,
            rng,
            config,
            normalization,
            best_val,
            best_quality,
            data,
        } = state;
        let plain = SamplerConfig {
            batch: config.batch,
            max_contexts: config.max_contexts,
            targets: config.targets_per_sequence,
            contexts_in_targets: config.contexts_in_targets,
            joint_targets: 0,
            single_modality: config.single_modality,
            prefix_contexts: config.prefix_contexts,
            warp: None,
        };
        // Training batches are warped with --augment; validation always sees plain sequences.
        let sampler = Sampler::new(SamplerConfig {
            warp: config.augment,
            joint_targets: config.joint_targets,
            ..plain
        });
        // Held-out frames are read once, uncached: the validation batches are kept.
        let mut val = SequenceStore::open(
            split.val.clone(),
            config.model.image_size as u32,
            0,
            config.camera.as_deref(),
            (
                config.model.joint_count(),
                "the training data's first sequence",
            ),
        )?;
        let pool = if val.is_empty() { &mut train } else { &mut val };
        let mut val_rng = Pcg64::seed_from_u64(config.seed ^ VAL_STREAM);
        let lengths = pool.lengths();
        let val_set = (0..config.val_batches)
            .map(|_| {
                let selection = Sampler::new(plain).draw(&lengths, &mut val_rng);
                Ok(pool.batch(&selection, &normalization)?.0)
            })
            .collect::<Result<_, TrainError>>()?;
        // Up to `quality_sequences` held-out sequences, evenly spread over them.
        let n = config.quality_sequences.min(val.len());
        let quality_set = (0..n)
            .map(|i| val.read(i * val.len() / n))
            .collect::<Result<_, _>>()?;
        let batches = BatchStream::spawn(train, sampler, normalization.clone(), rng.clone())?;
        Ok(Trainer {
            config,
            out: out.to_path_buf(),
            model,
            optim,
            rng,
            step,
            batches,
            val_ids: split.val_ids,
            normalization,
            val_set,
            quality_set,
            log,
            best_val,
            best_quality,
            data,
            device: devices[0].clone(),
            devices,
        })
    }

    /// Steps completed.
    pub fn step_count(&self) -> u64 {
        self.step
    }

    /// The run's settings.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// Write the final and best models with f16 weights from now on (a resumed run asked
    /// for the smaller files); the next checkpoint keeps it.
    pub fn write_half(&mut self) {
        self.config.half = true;
    }

    /// The dataset root the run trains on.
    pub fn data(&self) -> Option<&Path> {
        self.data.as_deref()
    }

    /// Held-out sequence ids.
    pub fn val_ids(&self) -> &[u32] {
        &self.val_ids
    }

    /// True when no id is held out (`val_fraction` 0 or a one-id dataset): the validation loss
    /// is measured on training sequences and says nothing about unseen ones.
    pub fn validates_on_training_data(&self) -> bool {
        self.val_ids.is_empty()
    }

    /// One optimiser step on a fresh batch; a non-finite loss stops before touching the weights.
    pub fn step(&mut self) -> Result<(LossValues, f64), TrainError> {
        let drawn = self.batches.next()?;
        self.rng = drawn.rng;
        let (values, grads) = gradients(
            &self.model,
            &drawn.batch,
            &drawn.joint_targets,
            &self.config,
            &self.devices,
        )?;
        if !values.total.is_finite() {
            return Err(TrainError::NonFinite {
                step: self.step + 1,
                value: values.total,
            });
        }
        let lr = self
            .config
            .schedule
            .rate(self.config.lr, self.step, self.config.steps);
        self.model = self.optim.step(lr, self.model.clone(), grads);
        self.step += 1;
        Ok((values, lr))
    }

    /// Mean losses over the fixed validation batches: on their targets, and on reconstructing
    /// their contexts.
    pub fn validate(&self) -> Result<(LossValues, LossValues), TrainError> {
        let contexts: Vec<Batch> = self
            .val_set
            .iter()
            .map(Batch::contexts_as_targets)
            .collect();
        Ok((self.mean_loss(&self.val_set)?, self.mean_loss(&contexts)?))
    }

    fn mean_loss(&self, batches: &[Batch]) -> Result<LossValues, TrainError> {
        let values = batches
            .iter()
            .map(|batch| {
                let batch = tensors(batch, &self.device)?;
                let prediction = self.model.forward(&batch)?;
                Ok(self.model.loss(&prediction, &batch, 0.0)?.values())
            })
            .collect::<Result<Vec<_>, TrainError>>()?;
        Ok(LossValues::mean(&values))
    }

    /// Train to `config.steps`, validating, logging and checkpointing on the way; writes the
    /// final model to `out/model.dmbn` (f16 weights when `config.half`) and returns its path.
    pub fn run(&mut self, mut on_progress: impl FnMut(&Progress)) -> Result<PathBuf, TrainError> {
        let mut timer = (Instant::now(), self.step);
        let mut last_val = None;
        while self.step < self.config.steps {
            let (values, lr) = self.step()?;
            let step = self.step;
            let elapsed = timer.0.elapsed().as_secs_f64();
            let steps_per_s = (step - timer.1) as f64 / elapsed.max(1e-9);
            let validating = step % self.config.val_every == 0 || step == self.config.steps;
            let val = if validating {
                let (v, c) = self.validate()?;
                if self.best_val.is_none_or(|(_, best)| v.total < best) {
                    self.best_val = Some((step, v.total));
                }
                last_val = Some(v.total);
                Some((v, c))
            } else {
                None
            };
            let quality = if validating {
                self.validate_quality()?
            } else {
                None
            };
            self.log.write(&Metrics {
                step,
                lr,
                loss: values.total,
                image_nll: values.image_nll,
                joint_nll: values.joint_nll,
                image_mse: values.image_mse,
                joint_mse: values.joint_mse,
                kl: self.model.latent_size().map(|_| values.kl),
                val_loss: val.map(|(v, _)| v.total),
                val_image_mse: val.map(|(v, _)| v.image_mse),
                val_joint_mse: val.map(|(v, _)| v.joint_mse),
                val_context_loss: val.map(|(_, c)| c.total),
                val_context_image_mse: val.map(|(_, c)| c.image_mse),
                val_context_joint_mse: val.map(|(_, c)| c.joint_mse),
                val_quality: quality,
                steps_per_s,
            })?;
            if step % self.config.checkpoint_every == 0 || step == self.config.steps {
                self.checkpoint()?;
            }
            on_progress(&Progress {
                step,
                steps: self.config.steps,
                loss: values.total,
                val_loss: last_val,
                steps_per_s,
            });
            if elapsed > 5.0 {
                timer = (Instant::now(), step);
            }
        }
        let path = self.out.join("model.dmbn");
        write_atomic(
            &path,
            &model::save_bytes(&self.model, &self.normalization, self.config.half)?,
        )?;
        Ok(path)
    }

    /// The quality benchmark on up to `config.quality_sequences` held-out sequences (evenly
    /// spread over them); a better [`ValQuality::score`] than any before is written to
    /// `out/best.dmbn`. `None` when it is off or there is nothing to score.
    pub fn validate_quality(&mut self) -> Result<Option<ValQuality>, TrainError> {
        if self.quality_set.is_empty() {
            return Ok(None);
        }
        let picked: Vec<&Sequence> = self.quality_set.iter().collect();
        let bytes = model::save_bytes(&self.model, &self.normalization, false)?;
        let predictor = Predictor::from_bytes(&bytes)?;
        let Some(quality) = ValQuality::measure(&predictor, &picked)? else {
            return Ok(None);
        };
        let score = quality.score();
        if score.is_finite() && self.best_quality.is_none_or(|(_, best)| score < best) {
            self.best_quality = Some((self.step, score));
            let bytes = model::save_bytes(&self.model, &self.normalization, self.config.half)?;
            write_atomic(&self.best_path(), &bytes)?;
        }
        Ok(Some(quality))
    }

    /// Where the model with the best validation quality is kept.
    pub fn best_path(&self) -> PathBuf {
        self.out.join("best.dmbn")
    }

    /// The best validation quality so far and its step.
    pub fn best_quality(&self) -> Option<(u64, f32)> {
        self.best_quality
    }

    /// Write a checkpoint of the current state.
    pub fn checkpoint(&self) -> Result<(), TrainError> {
        let model_bytes = model::save_bytes(&self.model, &self.normalization, false)?;
        let optim_bytes = self
            .optim
            .into_bytes()
            .map_err(|e| TrainError::Checkpoint {
                path: Checkpoint::dir(&self.out),
                message: format!("optimizer: {e:?}"),
            })?;
        let state = CheckpointState {
            step: self.step,
            rng: self.rng.clone(),
            config: self.config.clone(),
            normalization: self.normalization.clone(),
            best_val: self.best_val,
            best_quality: self.best_quality,
            data: self.data.clone(),
        };
        Checkpoint::write(&self.out, &model_bytes, &optim_bytes, &state)
    }
}

/// Adam with gradient clipping by norm, per parameter tensor (burn's `GradientClipping::Norm`).
fn optimizer(config: &TrainConfig) -> ModuleOptimizer {
    AdamConfig::new()
        .with_grad_clipping(Some(GradientClippingConfig::Norm(config.clip_norm)))
        .init()
}

/// The store of `sequences` of `split` (the run's training sequences), their joints checked
/// against the model's count, frames of the run's camera and size.
fn open_store(
    sequences: &[crate::data::SequenceRef],
    config: &TrainConfig,
    split: &Split,
) -> Result<SequenceStore, TrainError> {
    let width = config.model.joint_count();
    let reference = if split.joints.0 == width {
        "the dataset's first sequence"
    } else {
        "the model being trained"
    };
    Ok(SequenceStore::open(
        sequences.to_vec(),
        config.model.image_size as u32,
        config.frame_cache_mib << 20,
        config.camera.as_deref(),
        (width, reference),
    )?)
}
