//! The `train` command line's flags.
use std::path::PathBuf;

use clap::{Parser, ValueEnum};

use dmbn::model::{ModelConfig, ModelKind};
use dmbn::train::{JointStageFit, TrainConfig, TrainDevices};

/// `--model`: the command line's names of [`ModelKind`].
#[derive(Clone, Copy, ValueEnum)]
pub enum ModelArg {
    /// DMBN, time as an input channel (the original)
    Dmbn,
    /// DMBN-PTE, positional time encoding (the paper's fix)
    Pte,
    /// The attentive model: DMBN-PTE's encodings, cross-attention over the context times
    Attn,
}

impl From<ModelArg> for ModelKind {
    fn from(arg: ModelArg) -> Self {
        match arg {
            ModelArg::Dmbn => ModelKind::Dmbn,
            ModelArg::Pte => ModelKind::Pte,
            ModelArg::Attn => ModelKind::Attn,
        }
    }
}

/// `--initialization`: how fresh weights are drawn.
#[derive(Clone, Copy, ValueEnum)]
pub enum InitializationArg {
    /// He-uniform weights, zero biases (the project's)
    He,
    /// Glorot-uniform weights, zero biases (the original Keras model's; dmbn and pte)
    Glorot,
}

/// `--joint-scale`: how the joint normalisation scales the arm angles.
#[derive(Clone, Copy, ValueEnum)]
pub enum JointScaleArg {
    /// Each joint standardised on its own
    PerJoint,
    /// One scale for the six arm angles: the loss counts a radian alike on every joint
    Shared,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ScheduleArg {
    Constant,
    Cosine,
    Step,
}

/// Train DMBN, DMBN-PTE or the attentive model. Writes metrics.jsonl, checkpoint/ (every --checkpoint-every
/// steps, atomically) and, at the end, model.dmbn into --out.
#[derive(Parser)]
#[command(name = "train", version)]
pub struct Args {
    /// Dataset root in the DMBN layout (ours or the original); with --resume, the run's own
    /// unless given.
    #[arg(long, required_unless_present = "resume")]
    pub data: Option<PathBuf>,
    /// Which network (with --resume or --init, the checkpoint's or the file's: may be left out).
    #[arg(long, value_enum, required_unless_present_any = ["resume", "init"])]
    pub model: Option<ModelArg>,
    /// Start from this model file's weights instead of fresh weights (train a shipped model
    /// longer, or fine-tune it on other data); the network, frame size and σ floor are the
    /// file's, the joint normalisation is fitted on --data's training ids as for a fresh run.
    #[arg(long, conflicts_with = "resume")]
    pub init: Option<PathBuf>,
    /// Output folder for metrics, checkpoints and the final model.
    #[arg(long)]
    pub out: PathBuf,
    /// Optimiser steps in the whole run (with --resume: extends or keeps the run's).
    #[arg(long)]
    pub steps: Option<u64>,
    /// Seed of the weights and of the batch sampling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Sequences per batch.
    #[arg(long, default_value_t = defaults().batch)]
    pub batch: usize,
    /// Largest number of contexts per sequence (each draws 1..=max).
    #[arg(long, default_value_t = defaults().max_contexts)]
    pub max_contexts: usize,
    /// Targets per sequence.
    #[arg(long, default_value_t = defaults().targets_per_sequence)]
    pub targets_per_sequence: usize,
    /// Targets ⊇ contexts: each sequence's contexts lead its --targets-per-sequence targets
    /// (the reference CNP's training); otherwise every target is another step.
    #[arg(long)]
    pub contexts_in_targets: bool,
    /// Joint-only targets per sequence on top of the full ones: the joints are supervised at
    /// that many more steps, at a small cost (no frame is decoded for them).
    #[arg(long, default_value_t = defaults().joint_targets)]
    pub joint_targets: usize,
    /// Fraction of training sequences observed through one modality alone (blend c = 1 or 0,
    /// half each), so that frames-only and joints-only observation are trained; the rest draw
    /// c ~ U(0, 1).
    #[arg(long, default_value_t = defaults().single_modality)]
    pub single_modality: f32,
    /// Fraction of training sequences observed only in their first 10-90% (targets anywhere):
    /// forecasting the rest of an action from its start, as `dmbn score --scenario extrap`
    /// and the page's live mode ask.
    #[arg(long, default_value_t = defaults().prefix_contexts)]
    pub prefix_contexts: f32,
    /// Frame size the model works at (64 or 128; frames are resized when read).
    #[arg(long, default_value_t = defaults().model.image_size)]
    pub image_size: usize,
    /// Filters of the image decoder's convolutions before its heads, comma-separated: one per
    /// upsampling block, then two at full resolution (the original's at 64 px:
    /// 256,128,64,64,32,16,8). Fewer filters decode a frame with fewer multiply-adds.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["resume", "init"])]
    pub decoder_filters: Option<Vec<usize>>,
    /// Run the image decoder's two tail convolutions at half resolution, before the last
    /// upsampling: only the heads work at full resolution (9.8 M multiply-adds a frame
    /// instead of 16 M with the half-width filters; the page's live mode).
    #[arg(long, conflicts_with_all = ["resume", "init"])]
    pub coarse_tail: bool,
    /// Filters of the image encoder's conv blocks, comma-separated, one per block (the
    /// original's at 64 px: 32,64,128,128,256). Fewer filters encode an observation with
    /// fewer multiply-adds (live mode encodes each new one before it forecasts).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["resume", "init"])]
    pub encoder_filters: Option<Vec<usize>>,
    /// The attentive model: read the joints from each observed frame, and start the joint
    /// decoder from them where joints are not observed (frames only: the imitation
    /// benchmark, `dmbn imitate`). With --init, a file without the read-out gets one that
    /// reads nothing yet.
    #[arg(long, conflicts_with = "resume")]
    pub frame_joints: bool,
    /// The attentive model: a latent path of L values, a global z drawn once per sampled
    /// future (`dmbn sample`, `imitate --samples`), trained with its posterior. With --init, a
    /// file without one gets one that adds nothing yet.
    #[arg(long, conflicts_with = "resume")]
    pub latent: Option<usize>,
    /// Weight of the latent path's KL(posterior ‖ prior), nats per sequence, in the objective.
    #[arg(long, default_value_t = defaults().latent_kl)]
    pub latent_kl: f64,
    /// Free nats: the latent path's KL is not penalised below this many nats per sequence.
    #[arg(long, default_value_t = defaults().latent_free_nats)]
    pub latent_free_nats: f64,
    /// Base learning rate (Adam).
    #[arg(long, default_value_t = defaults().lr)]
    pub lr: f64,
    /// Learning-rate schedule.
    #[arg(long, value_enum, default_value = "constant")]
    pub schedule: ScheduleArg,
    /// Gradient clipping: largest norm of each parameter tensor's gradient (clipped one by one).
    #[arg(long, default_value_t = defaults().clip_norm)]
    pub clip_norm: f32,
    /// Weight of the joint NLL in the loss (the original's 0.01).
    #[arg(long, default_value_t = defaults().model.joint_weight)]
    pub joint_weight: f64,
    /// The attentive model: weight of the mean squared error of the frame it draws before its
    /// gate mixes it with the observed ones, so that it learns to draw everywhere, not only
    /// where the gate is shut (forecasting far from the observations needs it).
    #[arg(long, default_value_t = defaults().drawn_frame_weight)]
    pub drawn_frame_weight: f64,
    /// β-NLL (Seitzer et al. 2022): each value's NLL weighed by its σ^(2β), in [0, 1]. The
    /// plain NLL (0, the paper's) lets the pixels a model is sure of outweigh the moving arm
    /// in the mean's gradient; 1 gives every mean the squared error's gradient.
    #[arg(long, default_value_t = defaults().beta_nll)]
    pub beta_nll: f64,
    /// Lower bound of every predicted σ.
    #[arg(long, default_value_t = defaults().model.sigma_floor)]
    pub sigma_floor: f64,
    /// Fraction of sequence ids held out for validation (the last ids; at least one when it is
    /// above 0). 0 holds none out: the validation loss is then measured on training sequences
    /// (said when the run starts) and no best.dmbn is kept.
    #[arg(long, default_value_t = defaults().val_fraction)]
    pub val_fraction: f64,
    /// Validate every this many steps.
    #[arg(long, default_value_t = defaults().val_every)]
    pub val_every: u64,
    /// Write a checkpoint every this many steps.
    #[arg(long, default_value_t = defaults().checkpoint_every)]
    pub checkpoint_every: u64,
    /// Held-out sequences the quality benchmark (`dmbn score`'s interp and extrap against
    /// the trivial baselines) scores at each validation; the best model so far is kept as
    /// best.dmbn in --out. 0 turns it off.
    #[arg(long, default_value_t = defaults().quality_sequences)]
    pub quality_sequences: usize,
    /// How fresh weights are drawn (not with --init): he (the project's) or glorot (the
    /// original Keras model's, for the paper's own recipe; dmbn and pte only).
    #[arg(long, value_enum, default_value = "he")]
    pub initialization: InitializationArg,
    /// How the joints are normalised (fitted on the training data): per-joint standardises
    /// each joint; shared divides the six arm angles by one scale, so that the loss counts a
    /// radian the same on every joint, as the quality benchmark's joint RMSE does (for data
    /// where one joint sweeps radians and the others tenths, such as the original DMBN
    /// data's wrist). A resumed run keeps its run's.
    #[arg(
        long,
        value_enum,
        default_value = "per-joint",
        conflicts_with = "resume"
    )]
    pub joint_scale: JointScaleArg,
    /// Camera whose frames the model sees: a sub-folder of that name in each sequence folder
    /// (see docs/architecture.md, the DMBN layout); default: the frames in the sequence folder
    /// itself. One camera a model. A resumed run keeps its run's.
    #[arg(long, conflicts_with = "resume")]
    pub camera: Option<String>,
    /// Continue the run in --out from its last checkpoint (same settings).
    #[arg(long)]
    pub resume: bool,
    /// Where to train: cpu, wgpu (burn's wgpu backend: Vulkan, Metal or DX12; wgpu's choice
    /// of adapter), wgpu:N (the N-th discrete GPU) or cuda[:N]. The GPU backends are cargo
    /// features (`--features wgpu`, `--features cuda`). A comma-separated list (--devices
    /// wgpu:0,wgpu:1) trains data-parallel: each step's --batch is split evenly between the
    /// devices, the model and optimiser on the first. A run may resume on other devices.
    #[arg(
        long = "device",
        visible_alias = "devices",
        default_value = "cpu",
        value_parser = |s: &str| s.parse::<TrainDevices>()
    )]
    pub devices: TrainDevices,
    /// Time-warp augmentation (the paper's): random sections sped up or slowed down (0.5-2x)
    /// and repeated frames inserted, in 80% of the training sequences.
    #[arg(long)]
    pub augment: bool,
    /// With --augment: draw each freeze's length as a fraction of the warped sequence from
    /// LOW-HIGH (e.g. 0.05-0.9, freezes of any length up to most of the action) instead of
    /// 3-15 repeated steps.
    #[arg(long, value_parser = parse_fraction_range, requires = "augment")]
    pub freeze_fraction: Option<[f64; 2]>,

    /// MiB of decoded frames kept in memory: training reads frames from disk as its batches
    /// need them (on a thread of its own, a batch ahead), so memory does not grow with the
    /// dataset; more only saves decoding, the batches are the same. A resumed run keeps its
    /// run's.
    #[arg(long, default_value_t = defaults().frame_cache_mib, conflicts_with = "resume")]
    pub frame_cache_mib: usize,

    /// Then fit the joint stage to the final model (a second stage in joint space that turns
    /// the joints the network reads from frames alone into the trajectory: `dmbn imitate`,
    /// the page's frames-only joints): the network reads --joint-stage-draws glimpse layouts
    /// of every training sequence; the stage's σ is fitted on the validation ids' reads. With
    /// --init FILE --steps 0, adds a stage to FILE's network as it is (its σ scales kept).
    // The stage's old name, `--mirror` (and `--mirror-*` below), kept for old commands.
    #[arg(long, alias = "mirror")]
    pub joint_stage: bool,
    /// Adam steps of the joint stage's fit.
    #[arg(long, alias = "mirror-steps", requires = "joint_stage")]
    #[arg(default_value_t = JointStageFit::default().steps)]
    pub joint_stage_steps: u64,
    /// Glimpse layouts (2-8 glimpses) read per sequence for the joint stage.
    #[arg(long, alias = "mirror-draws", requires = "joint_stage")]
    #[arg(default_value_t = JointStageFit::default().draws)]
    pub joint_stage_draws: usize,
    /// Width of the joint stage's three hidden layers.
    #[arg(long, alias = "mirror-width", requires = "joint_stage")]
    #[arg(default_value_t = JointStageFit::default().width)]
    pub joint_stage_width: usize,

    /// Store the final and best models' weights in f16 (half the size; a resumed run keeps
    /// the run's choice, and --half with --resume turns it on).
    #[arg(long)]
    pub half: bool,
}

/// `LOW-HIGH`, two fractions with 0 <= LOW <= HIGH < 1.
fn parse_fraction_range(s: &str) -> Result<[f64; 2], String> {
    let expected =
        || format!("expected LOW-HIGH with 0 <= LOW <= HIGH < 1 (e.g. 0.05-0.9), got {s:?}");
    let (lo, hi) = s.split_once('-').ok_or_else(expected)?;
    let (lo, hi): (f64, f64) = (
        lo.trim().parse().map_err(|_| expected())?,
        hi.trim().parse().map_err(|_| expected())?,
    );
    if !(0.0 <= lo && lo <= hi && hi < 1.0) {
        return Err(expected());
    }
    Ok([lo, hi])
}

/// The flags' defaults: the library's, so that they are written once.
fn defaults() -> TrainConfig {
    TrainConfig::new(ModelConfig::new(ModelKind::Pte), 1, 0)
}
