//! The `train` command line (native only).
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use dmbn::augment::TimeWarpConfig;
use dmbn::data::{id_list, write_atomic, JointScale};
use dmbn::model::{read_header, Initialization, ModelConfig, ModelKind};
use dmbn::train::{
    add_mirror, MirrorFit, MirrorStage, Schedule, Split, TrainConfig, TrainDevices, TrainError,
    Trainer,
};

/// `--model`: the command line's names of [`ModelKind`].
#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
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
enum InitializationArg {
    /// He-uniform weights, zero biases (the project's)
    He,
    /// Glorot-uniform weights, zero biases (the original Keras model's; dmbn and pte)
    Glorot,
}

/// `--joint-scale`: how the joint normalisation scales the arm angles.
#[derive(Clone, Copy, ValueEnum)]
enum JointScaleArg {
    /// Each joint standardised on its own
    PerJoint,
    /// One scale for the six arm angles: the loss counts a radian alike on every joint
    Shared,
}

#[derive(Clone, Copy, ValueEnum)]
enum ScheduleArg {
    Constant,
    Cosine,
    Step,
}

/// Train DMBN, DMBN-PTE or the attentive model. Writes metrics.jsonl, checkpoint/ (every --checkpoint-every
/// steps, atomically) and, at the end, model.dmbn into --out.
#[derive(Parser)]
#[command(name = "train", version)]
struct Args {
    /// Dataset root in the DMBN layout (ours or the original); with --resume, the run's own
    /// unless given.
    #[arg(long, required_unless_present = "resume")]
    data: Option<PathBuf>,
    /// Which network (with --resume or --init, the checkpoint's or the file's: may be left out).
    #[arg(long, value_enum, required_unless_present_any = ["resume", "init"])]
    model: Option<ModelArg>,
    /// Start from this model file's weights instead of fresh weights (train a shipped model
    /// longer, or fine-tune it on other data); the network, frame size and σ floor are the
    /// file's, the joint normalisation is fitted on --data's training ids as for a fresh run.
    #[arg(long, conflicts_with = "resume")]
    init: Option<PathBuf>,
    /// Output folder for metrics, checkpoints and the final model.
    #[arg(long)]
    out: PathBuf,
    /// Optimiser steps in the whole run (with --resume: extends or keeps the run's).
    #[arg(long)]
    steps: Option<u64>,
    /// Seed of the weights and of the batch sampling.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Sequences per batch.
    #[arg(long, default_value_t = defaults().batch)]
    batch: usize,
    /// Largest number of contexts per sequence (each draws 1..=max).
    #[arg(long, default_value_t = defaults().max_contexts)]
    max_contexts: usize,
    /// Targets per sequence.
    #[arg(long, default_value_t = defaults().targets_per_sequence)]
    targets_per_sequence: usize,
    /// Targets ⊇ contexts: each sequence's contexts lead its --targets-per-sequence targets
    /// (the reference CNP's training); otherwise every target is another step.
    #[arg(long)]
    contexts_in_targets: bool,
    /// Joint-only targets per sequence on top of the full ones: the joints are supervised at
    /// that many more steps, at a small cost (no frame is decoded for them).
    #[arg(long, default_value_t = defaults().joint_targets)]
    joint_targets: usize,
    /// Fraction of training sequences observed through one modality alone (blend c = 1 or 0,
    /// half each), so that frames-only and joints-only observation are trained; the rest draw
    /// c ~ U(0, 1).
    #[arg(long, default_value_t = defaults().single_modality)]
    single_modality: f32,
    /// Fraction of training sequences observed only in their first 10-90% (targets anywhere):
    /// forecasting the rest of an action from its start, as `dmbn score --scenario extrap`
    /// and the page's live mode ask.
    #[arg(long, default_value_t = defaults().prefix_contexts)]
    prefix_contexts: f32,
    /// Frame size the model works at (64 or 128; frames are resized when read).
    #[arg(long, default_value_t = defaults().model.image_size)]
    image_size: usize,
    /// Filters of the image decoder's convolutions before its heads, comma-separated: one per
    /// upsampling block, then two at full resolution (the original's at 64 px:
    /// 256,128,64,64,32,16,8). Fewer filters decode a frame with fewer multiply-adds.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["resume", "init"])]
    decoder_filters: Option<Vec<usize>>,
    /// Run the image decoder's two tail convolutions at half resolution, before the last
    /// upsampling: only the heads work at full resolution (9.8 M multiply-adds a frame
    /// instead of 16 M with the half-width filters; the page's live mode).
    #[arg(long, conflicts_with_all = ["resume", "init"])]
    coarse_tail: bool,
    /// Filters of the image encoder's conv blocks, comma-separated, one per block (the
    /// original's at 64 px: 32,64,128,128,256). Fewer filters encode an observation with
    /// fewer multiply-adds (live mode encodes each new one before it forecasts).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["resume", "init"])]
    encoder_filters: Option<Vec<usize>>,
    /// The attentive model: read the joints from each observed frame, and start the joint
    /// decoder from them where joints are not observed (frames only: the mirror, `dmbn
    /// imitate`). With --init, a file without the read-out gets one that reads nothing yet.
    #[arg(long, conflicts_with = "resume")]
    frame_joints: bool,
    /// The attentive model: a latent path of L values, a global z drawn once per sampled
    /// future (`dmbn sample`, `imitate --samples`), trained with its posterior. With --init, a
    /// file without one gets one that adds nothing yet.
    #[arg(long, conflicts_with = "resume")]
    latent: Option<usize>,
    /// Weight of the latent path's KL(posterior ‖ prior), nats per sequence, in the objective.
    #[arg(long, default_value_t = defaults().latent_kl)]
    latent_kl: f64,
    /// Free nats: the latent path's KL is not penalised below this many nats per sequence.
    #[arg(long, default_value_t = defaults().latent_free_nats)]
    latent_free_nats: f64,
    /// Base learning rate (Adam).
    #[arg(long, default_value_t = defaults().lr)]
    lr: f64,
    /// Learning-rate schedule.
    #[arg(long, value_enum, default_value = "constant")]
    schedule: ScheduleArg,
    /// Gradient clipping: largest norm of each parameter tensor's gradient (clipped one by one).
    #[arg(long, default_value_t = defaults().clip_norm)]
    clip_norm: f32,
    /// Weight of the joint NLL in the loss (the original's 0.01).
    #[arg(long, default_value_t = defaults().model.joint_weight)]
    joint_weight: f64,
    /// The attentive model: weight of the mean squared error of the frame it draws before its
    /// gate mixes it with the observed ones, so that it learns to draw everywhere, not only
    /// where the gate is shut (forecasting far from the observations needs it).
    #[arg(long, default_value_t = defaults().drawn_frame_weight)]
    drawn_frame_weight: f64,
    /// β-NLL (Seitzer et al. 2022): each value's NLL weighed by its σ^(2β), in [0, 1]. The
    /// plain NLL (0, the paper's) lets the pixels a model is sure of outweigh the moving arm
    /// in the mean's gradient; 1 gives every mean the squared error's gradient.
    #[arg(long, default_value_t = defaults().beta_nll)]
    beta_nll: f64,
    /// Lower bound of every predicted σ.
    #[arg(long, default_value_t = defaults().model.sigma_floor)]
    sigma_floor: f64,
    /// Fraction of sequence ids held out for validation (the last ids; at least one when it is
    /// above 0). 0 holds none out: the validation loss is then measured on training sequences
    /// (said when the run starts) and no best.dmbn is kept.
    #[arg(long, default_value_t = defaults().val_fraction)]
    val_fraction: f64,
    /// Validate every this many steps.
    #[arg(long, default_value_t = defaults().val_every)]
    val_every: u64,
    /// Write a checkpoint every this many steps.
    #[arg(long, default_value_t = defaults().checkpoint_every)]
    checkpoint_every: u64,
    /// Held-out sequences the quality benchmark (`dmbn score`'s interp and extrap against
    /// the trivial baselines) scores at each validation; the best model so far is kept as
    /// best.dmbn in --out. 0 turns it off.
    #[arg(long, default_value_t = defaults().quality_sequences)]
    quality_sequences: usize,
    /// How fresh weights are drawn (not with --init): he (the project's) or glorot (the
    /// original Keras model's, for the paper's own recipe; dmbn and pte only).
    #[arg(long, value_enum, default_value = "he")]
    initialization: InitializationArg,
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
    joint_scale: JointScaleArg,
    /// Camera whose frames the model sees: a sub-folder of that name in each sequence folder
    /// (see docs/architecture.md, the DMBN layout); default: the frames in the sequence folder
    /// itself. One camera a model. A resumed run keeps its run's.
    #[arg(long, conflicts_with = "resume")]
    camera: Option<String>,
    /// Continue the run in --out from its last checkpoint (same settings).
    #[arg(long)]
    resume: bool,
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
    devices: TrainDevices,
    /// Time-warp augmentation (the paper's): random sections sped up or slowed down (0.5-2x)
    /// and repeated frames inserted, in 80% of the training sequences.
    #[arg(long)]
    augment: bool,
    /// With --augment: draw each freeze's length as a fraction of the warped sequence from
    /// LOW-HIGH (e.g. 0.05-0.9, freezes of any length up to most of the action) instead of
    /// 3-15 repeated steps.
    #[arg(long, value_parser = parse_fraction_range, requires = "augment")]
    freeze_fraction: Option<[f64; 2]>,

    /// MiB of decoded frames kept in memory: training reads frames from disk as its batches
    /// need them (on a thread of its own, a batch ahead), so memory does not grow with the
    /// dataset; more only saves decoding, the batches are the same. A resumed run keeps its
    /// run's.
    #[arg(long, default_value_t = defaults().frame_cache_mib, conflicts_with = "resume")]
    frame_cache_mib: usize,

    /// Then fit the mirror stage to the final model (a second stage in joint space that turns
    /// the joints the network reads from frames alone into the trajectory: `dmbn imitate`,
    /// the page's frames-only joints): the network reads --mirror-draws glimpse layouts of
    /// every training sequence; the stage's σ is fitted on the validation ids' reads. With
    /// --init FILE --steps 0, adds a stage to FILE's network as it is (its σ scales kept).
    #[arg(long)]
    mirror: bool,
    /// Adam steps of the mirror stage's fit.
    #[arg(long, default_value_t = MirrorFit::default().steps, requires = "mirror")]
    mirror_steps: u64,
    /// Glimpse layouts (2-8 glimpses) read per sequence for the mirror stage.
    #[arg(long, default_value_t = MirrorFit::default().draws, requires = "mirror")]
    mirror_draws: usize,
    /// Width of the mirror stage's three hidden layers.
    #[arg(long, default_value_t = MirrorFit::default().width, requires = "mirror")]
    mirror_width: usize,

    /// Store the final and best models' weights in f16 (half the size; a resumed run keeps
    /// the run's choice, and --half with --resume turns it on).
    #[arg(long)]
    half: bool,
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

pub fn main() -> ExitCode {
    let args = Args::parse();
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The model config in the header of the `--init` file.
fn init_config(path: &std::path::Path) -> Result<ModelConfig, TrainError> {
    let bytes = std::fs::read(path).map_err(|e| TrainError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    read_header(&bytes)
        .map(|header| header.config)
        .map_err(|e| TrainError::config("init", format!("{}: {e}", path.display())))
}

/// The flags' defaults: the library's, so that they are written once.
fn defaults() -> TrainConfig {
    TrainConfig::new(ModelConfig::new(ModelKind::Pte), 1, 0)
}

fn run(args: Args) -> Result<(), TrainError> {
    if args.mirror {
        mirror_fit(&args).validate()?;
    }
    if args.mirror && args.steps == Some(0) {
        return mirror_only(&args);
    }
    let model = args.model.map(ModelKind::from);
    let mut trainer = if args.resume {
        let mut trainer =
            Trainer::resume_on(&args.devices, args.data.as_deref(), &args.out, args.steps)?;
        if args.half {
            trainer.write_half();
        }
        let trained = trainer.config().model.kind;
        if model.is_some_and(|m| m != trained) {
            return Err(TrainError::config(
                "model",
                format!(
                    "the checkpoint in {} trains {trained}, not {}: leave --model out to resume it",
                    args.out.display(),
                    model.map_or(String::new(), |m| m.to_string())
                ),
            ));
        }
        trainer
    } else {
        let steps = args.steps.ok_or_else(|| TrainError::Config {
            field: "steps",
            message: "missing: pass --steps N".into(),
        })?;
        // Required unless resuming (clap checks).
        let Some(data) = args.data.as_deref() else {
            return Err(TrainError::config("data", "missing: pass --data"));
        };
        let init = args.init.as_deref().map(init_config).transpose()?;
        let kind = match (model, &init) {
            (Some(kind), Some(file)) if kind != file.kind => {
                return Err(TrainError::config(
                    "model",
                    format!(
                        "--init holds a {} model, not {kind}: leave --model out to train it",
                        file.kind
                    ),
                ))
            }
            (Some(kind), _) => kind,
            (None, Some(file)) => file.kind,
            (None, None) => return Err(TrainError::config("model", "missing: pass --model")),
        };
        // A file's network, frame size and σ floor are its own; the loss's joint weight is the run's.
        let model = init
            .unwrap_or_else(|| {
                ModelConfig::new(kind)
                    .with_image_size(args.image_size)
                    .with_sigma_floor(args.sigma_floor)
                    .with_decoder_filters(args.decoder_filters.clone())
                    .with_coarse_tail(args.coarse_tail.then_some(true))
                    .with_encoder_filters(args.encoder_filters.clone())
            })
            .with_joint_weight(args.joint_weight)
            .with_mirror(None);
        let model = if args.frame_joints {
            model.with_frame_joints(Some(true))
        } else {
            model
        };
        let model = match (args.latent, model.latent) {
            (Some(asked), Some(has)) if asked != has => {
                return Err(TrainError::config(
                    "latent",
                    format!(
                        "--init has a latent path of {has} values, not {asked}: leave --latent out"
                    ),
                ))
            }
            (Some(asked), _) => model.with_latent(Some(asked)),
            (None, _) => model,
        };
        let mut config = TrainConfig::new(model, steps, args.seed);
        config.batch = args.batch;
        config.max_contexts = args.max_contexts;
        config.targets_per_sequence = args.targets_per_sequence;
        config.contexts_in_targets = args.contexts_in_targets;
        config.joint_targets = args.joint_targets;
        config.single_modality = args.single_modality;
        config.prefix_contexts = args.prefix_contexts;
        config.lr = args.lr;
        config.schedule = match args.schedule {
            ScheduleArg::Constant => Schedule::Constant,
            ScheduleArg::Cosine => Schedule::Cosine {
                final_fraction: 0.05,
            },
            ScheduleArg::Step => Schedule::Step {
                every: (steps / 3).max(1),
                gamma: 0.3,
            },
        };
        config.clip_norm = args.clip_norm;
        config.drawn_frame_weight = args.drawn_frame_weight;
        config.beta_nll = args.beta_nll;
        config.latent_kl = args.latent_kl;
        config.latent_free_nats = args.latent_free_nats;
        config.val_fraction = args.val_fraction;
        config.val_every = args.val_every;
        config.checkpoint_every = args.checkpoint_every;
        config.quality_sequences = args.quality_sequences;
        config.augment = args.augment.then(|| TimeWarpConfig {
            freeze_fraction: args.freeze_fraction,
            ..TimeWarpConfig::default()
        });
        config.init = args.init.clone();
        config.initialization = match args.initialization {
            InitializationArg::He => Initialization::He,
            InitializationArg::Glorot => Initialization::Glorot,
        };
        config.half = args.half;
        config.frame_cache_mib = args.frame_cache_mib;
        config.joint_scale = match args.joint_scale {
            JointScaleArg::PerJoint => JointScale::PerJoint,
            JointScaleArg::Shared => JointScale::Shared,
        };
        config.camera = args.camera.clone();
        Trainer::new_on(&args.devices, data, &args.out, config)?
    };
    let steps = trainer.config().steps;
    let bar = ProgressBar::new(steps).with_position(trainer.step_count());
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {pos}/{len} {msg} [{elapsed_precise} < {eta_precise}]",
        )
        .expect("valid template"),
    );
    eprintln!(
        "training {} on {} ({}; validation ids {}), output in {}",
        trainer.config().model.kind,
        trainer
            .data()
            .map_or("?".into(), |d| d.display().to_string()),
        args.devices,
        id_list(trainer.val_ids()),
        args.out.display()
    );
    if trainer.validates_on_training_data() {
        eprintln!(
            "note: no id is held out (--val-fraction 0, or one id in the dataset): the validation \
             loss is measured on training sequences, and no best.dmbn is kept"
        );
    }
    let path = trainer.run(|p| {
        bar.set_position(p.step);
        let val = p.val_loss.map_or("-".to_string(), |v| format!("{v:.4}"));
        bar.set_message(format!(
            "loss {:.4} val {val} {:.2} steps/s",
            p.loss, p.steps_per_s
        ));
    })?;
    bar.finish();
    if args.mirror {
        let data = trainer
            .data()
            .ok_or_else(|| TrainError::config("data", "missing: pass --data"))?;
        let config = trainer.config();
        let split = Split::open_camera(data, config.val_fraction, config.camera.as_deref())?;
        fit_mirror_stage(&args, &split, config.camera.as_deref(), &path)?;
    }
    println!("wrote {}", path.display());
    if let Some((step, score)) = trainer.best_quality() {
        println!(
            "wrote {} (step {step}: {score:.3} of the trivial baselines' error, validation ids)",
            trainer.best_path().display()
        );
    }
    Ok(())
}

/// `--init FILE --steps 0 --mirror`: FILE as it is (its network, normalisation and σ scales)
/// with a mirror stage, as --out/model.dmbn.
fn mirror_only(args: &Args) -> Result<(), TrainError> {
    let init = args.init.as_deref().ok_or_else(|| {
        TrainError::config(
            "init",
            "missing: --steps 0 --mirror fits a mirror stage to a model file's network: pass --init FILE",
        )
    })?;
    let Some(data) = args.data.as_deref() else {
        return Err(TrainError::config("data", "missing: pass --data"));
    };
    let split = Split::open_camera(data, args.val_fraction, args.camera.as_deref())?;
    let bytes = std::fs::read(init).map_err(|e| TrainError::Io {
        path: init.to_path_buf(),
        message: e.to_string(),
    })?;
    std::fs::create_dir_all(&args.out).map_err(|e| TrainError::Io {
        path: args.out.clone(),
        message: e.to_string(),
    })?;
    let path = args.out.join("model.dmbn");
    write_atomic(&path, &bytes)?;
    fit_mirror_stage(args, &split, args.camera.as_deref(), &path)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The `--mirror-*` flags' fit.
fn mirror_fit(args: &Args) -> MirrorFit {
    MirrorFit {
        width: args.mirror_width,
        draws: args.mirror_draws,
        steps: args.mirror_steps,
        seed: args.seed,
        ..MirrorFit::default()
    }
}

/// `--mirror`: the mirror stage fitted to the model file at `path` (rewritten with it), on
/// the CPU.
fn fit_mirror_stage(
    args: &Args,
    split: &Split,
    camera: Option<&str>,
    path: &std::path::Path,
) -> Result<(), TrainError> {
    let fit = mirror_fit(args);
    eprintln!(
        "fitting the mirror stage: {} training and {} validation sequences, {} layouts each",
        split.train.len(),
        split.val.len(),
        fit.draws
    );
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:30} {pos}/{len} {msg} [{elapsed_precise} < {eta_precise}]",
        )
        .expect("valid template"),
    );
    let started = std::time::Instant::now();
    let val = if split.validates_on_training_data() {
        &[][..]
    } else {
        &split.val[..]
    };
    add_mirror(
        path,
        &split.train,
        val,
        camera,
        fit,
        &burn::tensor::Device::flex().autodiff(),
        |stage| match stage {
            MirrorStage::Reading { done, total } => {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
                bar.set_message("sequences read");
                if done == total {
                    bar.suspend(|| {
                        eprintln!(
                            "read {total} sequences' glimpse layouts ({:.0?})",
                            started.elapsed()
                        )
                    });
                }
            }
            MirrorStage::Fitting(p) => {
                if p.step <= 500 {
                    bar.reset();
                }
                bar.set_length(fit.steps);
                bar.set_position(p.step);
                let message = format!(
                    "joint RMSE {:.4} rad, validation {:.4}",
                    p.rmse, p.held_out_rmse
                );
                if p.step % 5000 == 0 || p.step == fit.steps {
                    bar.suspend(|| {
                        eprintln!(
                            "mirror stage step {}/{}: {message} ({:.0?})",
                            p.step,
                            fit.steps,
                            started.elapsed()
                        )
                    });
                }
                bar.set_message(message);
            }
        },
    )?;
    bar.finish();
    Ok(())
}
