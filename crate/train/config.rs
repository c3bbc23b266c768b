use std::path::PathBuf;

use serde::{Deserialize, Deserializer, Serialize};

use super::TrainError;
use crate::augment::TimeWarpConfig;
use crate::data::JointScale;
use crate::model::{Initialization, ModelConfig, ModelKind};

/// Learning-rate schedule over the run, a pure function of the step (so resuming needs no
/// scheduler state).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Schedule {
    /// The base rate throughout.
    Constant,
    /// Cosine decay from the base rate to `final_fraction` of it at the last step.
    Cosine { final_fraction: f64 },
    /// Multiply by `gamma` every `every` steps.
    Step { every: u64, gamma: f64 },
}

impl Schedule {
    /// Learning rate at `step` (0-based) of `steps`, from the base rate `lr`: the cosine
    /// reaches `final_fraction` of `lr` at the last step (`steps - 1`).
    pub fn rate(&self, lr: f64, step: u64, steps: u64) -> f64 {
        match *self {
            Schedule::Constant => lr,
            Schedule::Cosine { final_fraction } => {
                let progress = (step as f64 / steps.saturating_sub(1).max(1) as f64).min(1.0);
                let floor = lr * final_fraction;
                floor + 0.5 * (lr - floor) * (1.0 + (std::f64::consts::PI * progress).cos())
            }
            Schedule::Step { every, gamma } => lr * gamma.powi((step / every.max(1)) as i32),
        }
    }
}

/// Everything that defines a training run; saved with every checkpoint so `--resume`
/// continues the same run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    /// The model trained: kind, frame size (frames are resized to it when read), σ floor and
    /// the joint NLL's weight in the loss. Checkpoints written before it held more than the
    /// kind read as `ModelConfig::new(kind)`, and `Checkpoint::read` restores the rest.
    #[serde(deserialize_with = "model_or_kind")]
    pub model: ModelConfig,
    /// Seed of the weights, the split-independent batch sampling and the blending draws.
    pub seed: u64,
    /// Optimiser steps in the whole run.
    pub steps: u64,
    /// Sequences per batch.
    pub batch: usize,
    /// Largest number of contexts per sequence (each draws 1..=max).
    pub max_contexts: usize,
    /// Targets per sequence.
    pub targets_per_sequence: usize,
    /// Targets ⊇ contexts: each sequence's contexts lead its targets (the reference CNP's
    /// training); otherwise targets are other steps.
    #[serde(default)]
    pub contexts_in_targets: bool,
    /// Joint-only targets per sequence on top of the full ones (joints supervised at more
    /// steps than frames are decoded for); their NLL is added with the joint weight.
    #[serde(default)]
    pub joint_targets: usize,
    /// Fraction of training sequences observed through one modality alone (c = 0 or 1); 0
    /// for the paper's c ~ U(0, 1) everywhere.
    #[serde(default)]
    pub single_modality: f32,
    /// Fraction of training sequences observed only in a prefix (forecasting the rest); 0 for
    /// contexts anywhere.
    #[serde(default)]
    pub prefix_contexts: f32,
    /// Base learning rate (Adam).
    pub lr: f64,
    /// Learning-rate schedule.
    pub schedule: Schedule,
    /// Gradient clipping: each parameter's gradient scaled to this norm at most (burn's
    /// `GradientClipping::Norm` works per tensor, not on one global norm).
    pub clip_norm: f32,
    /// The attentive model: weight of the mean squared error of the frame it draws, before its
    /// gate mixes it with the observed ones (through the gate it learns only where the gate is
    /// shut, and a forecast far from the observations needs it everywhere); 0 for none.
    #[serde(default)]
    pub drawn_frame_weight: f64,
    /// β of the β-NLL objective (see [`gaussian_loss`](crate::model::gaussian_loss)): each
    /// value's NLL weighed by its σ^(2β), so that what the model is unsure of (the moving
    /// arm) is learnt as well as what it is sure of; 0 for the paper's plain NLL.
    #[serde(default)]
    pub beta_nll: f64,
    /// A model with a latent path: weight of KL(posterior ‖ prior) of z (nats per sequence)
    /// in the objective, beside the per-value NLLs (see [`TrainConfig::DEFAULT_LATENT_KL`]).
    #[serde(default = "default_latent_kl")]
    pub latent_kl: f64,
    /// Free nats: the KL is not penalised below this many nats per sequence (Kingma et al.
    /// 2016's free bits), so the posterior can start to carry what the targets show before
    /// the decoder has learnt to read z (otherwise the path collapses onto its prior).
    #[serde(default)]
    pub latent_free_nats: f64,
    /// Fraction of sequence ids held out for validation, in [0, 1); 0 holds none out, and
    /// validation then runs on training sequences (the trainer says so).
    pub val_fraction: f64,
    /// Validate every this many steps.
    pub val_every: u64,
    /// Batches in the (fixed) validation set: at least 1.
    pub val_batches: usize,
    /// Write a checkpoint every this many steps.
    pub checkpoint_every: u64,
    /// Held-out sequences the quality benchmark scores at each validation (the best model is
    /// kept as `best.dmbn`); 0 for none.
    #[serde(default)]
    pub quality_sequences: usize,
    /// Time-warp augmentation of training sequences (the paper's, for DMBN-PTE), or none.
    #[serde(default)]
    pub augment: Option<TimeWarpConfig>,
    /// A model file whose weights the run starts from (fine-tuning, or training a shipped
    /// model longer), instead of fresh weights; its model config must be `model`'s kind and
    /// frame size. The joint normalisation is fitted on the run's training data either way.
    #[serde(default)]
    pub init: Option<PathBuf>,
    /// How fresh weights are drawn (ignored with `init`): He-uniform, or the original Keras
    /// model's Glorot-uniform for the paper's own recipe (DMBN and DMBN-PTE only: the
    /// attentive model's gates and read-out start from zero by design).
    #[serde(default)]
    pub initialization: Initialization,
    /// Write the final and best models with f16 weights (half the size); kept with the
    /// checkpoint so that a resumed run writes what the run would have.
    #[serde(default)]
    pub half: bool,
    /// MiB of decoded training frames kept in memory (the least recently used leave first):
    /// training reads frames from disk as batches need them instead of holding the dataset,
    /// so memory does not grow with it. More only saves decoding (which runs ahead on its own
    /// thread); the batches are the same for any size.
    #[serde(default = "default_frame_cache_mib")]
    pub frame_cache_mib: usize,
    /// How the joint normalisation, fitted on the training data, scales the arm angles: per
    /// joint, or one scale for all six so that the loss counts their radians alike.
    #[serde(default)]
    pub joint_scale: JointScale,
    /// The camera whose frames the model sees: a sub-folder of that name in every sequence
    /// folder (see [`crate::data`]); none: the default camera (`<k>.png`).
    #[serde(default)]
    pub camera: Option<String>,
}

/// [`TrainConfig::frame_cache_mib`]'s default: 21,000 frames at 64 px (all of 350 sequences of
/// 61 steps), 5,400 at 128 px.
fn default_frame_cache_mib() -> usize {
    256
}

fn default_latent_kl() -> f64 {
    TrainConfig::DEFAULT_LATENT_KL
}

impl TrainConfig {
    /// The KL's default weight: the NLLs are means per value, and a sequence's joints are
    /// about a hundred values (steps × D ≈ 700), so 1/700 would weigh the KL as the ELBO does;
    /// a little more keeps the prior close to what the posterior draws.
    pub const DEFAULT_LATENT_KL: f64 = 0.003;

    /// A run with the given model, seed and length: the defaults, in one place (the `train`
    /// binary's flags default to them).
    pub fn new(model: ModelConfig, steps: u64, seed: u64) -> TrainConfig {
        TrainConfig {
            model,
            seed,
            steps,
            batch: 8,
            max_contexts: 5,
            targets_per_sequence: 4,
            contexts_in_targets: false,
            joint_targets: 0,
            single_modality: 0.0,
            prefix_contexts: 0.0,
            lr: 1e-4,
            schedule: Schedule::Constant,
            clip_norm: 1.0,
            drawn_frame_weight: 0.0,
            beta_nll: 0.0,
            latent_kl: TrainConfig::DEFAULT_LATENT_KL,
            latent_free_nats: 0.0,
            val_fraction: 0.1,
            val_every: 200,
            val_batches: 8,
            checkpoint_every: 500,
            quality_sequences: 10,
            augment: None,
            init: None,
            initialization: Initialization::He,
            half: false,
            frame_cache_mib: default_frame_cache_mib(),
            joint_scale: JointScale::PerJoint,
            camera: None,
        }
    }

    /// Reject settings that would fail later or silently do nothing.
    pub fn validate(&self) -> Result<(), TrainError> {
        let positive = [
            ("steps", self.steps),
            ("batch", self.batch as u64),
            ("max_contexts", self.max_contexts as u64),
            ("targets_per_sequence", self.targets_per_sequence as u64),
            ("val_every", self.val_every),
            ("val_batches", self.val_batches as u64),
            ("checkpoint_every", self.checkpoint_every),
        ];
        for (field, value) in positive {
            if value == 0 {
                return Err(TrainError::config(field, "is 0: expected at least 1"));
            }
        }
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return Err(TrainError::config(
                "lr",
                format!("{}: expected a positive number", self.lr),
            ));
        }
        let weights = [
            ("drawn_frame_weight", self.drawn_frame_weight),
            ("latent_kl", self.latent_kl),
            ("latent_free_nats", self.latent_free_nats),
        ];
        for (field, weight) in weights {
            if !(weight.is_finite() && weight >= 0.0) {
                return Err(TrainError::config(
                    field,
                    format!("{weight}: expected a finite value >= 0"),
                ));
            }
        }
        if !(0.0..=1.0).contains(&self.beta_nll) {
            return Err(TrainError::config(
                "beta_nll",
                format!("{}: expected a value in [0, 1]", self.beta_nll),
            ));
        }
        if !(self.clip_norm.is_finite() && self.clip_norm > 0.0) {
            return Err(TrainError::config(
                "clip_norm",
                format!("{}: expected a positive number", self.clip_norm),
            ));
        }
        let fractions = [
            ("single_modality", self.single_modality),
            ("prefix_contexts", self.prefix_contexts),
        ];
        for (field, value) in fractions {
            if !(0.0..=1.0).contains(&value) {
                return Err(TrainError::config(
                    field,
                    format!("{value}: expected a fraction in [0, 1]"),
                ));
            }
        }
        if let Some(warp) = &self.augment {
            warp.validate()
                .map_err(|reason| TrainError::config("augment", reason.to_string()))?;
        }
        if self.initialization == Initialization::Glorot && self.model.kind == ModelKind::Attn {
            return Err(TrainError::config(
                "initialization",
                "glorot is for dmbn and pte: the attentive model's gates and read-out start from \
                 zero by design",
            ));
        }
        self.model.validate()?;
        Ok(())
    }
}

/// A model config, or only a model kind (settings written before the config moved in).
fn model_or_kind<'de, D: Deserializer<'de>>(d: D) -> Result<ModelConfig, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Model {
        Config(ModelConfig),
        Kind(ModelKind),
    }
    Ok(match Model::deserialize(d)? {
        Model::Config(config) => config,
        Model::Kind(kind) => ModelConfig::new(kind),
    })
}
