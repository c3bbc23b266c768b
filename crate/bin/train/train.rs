//! Training the network: a new run from the flags (fresh weights or `--init FILE`'s), or
//! `--resume`, with a progress bar.
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};

use dmbn::augment::TimeWarpConfig;
use dmbn::data::{id_list, JointScale};
use dmbn::model::{read_header, Initialization, ModelConfig, ModelKind};
use dmbn::train::{Schedule, TrainConfig, TrainError, Trainer};

use crate::args::{Args, InitializationArg, JointScaleArg, ScheduleArg};

/// Trains as the flags say, showing progress; the trainer and the final model file's path.
pub fn train(args: &Args) -> Result<(Trainer, PathBuf), TrainError> {
    let mut trainer = if args.resume {
        resume(args)?
    } else {
        new_run(args)?
    };
    let steps = trainer.config().steps;
    let bar = ProgressBar::new(steps).with_position(trainer.step_count());
    bar.set_style(progress_style());
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
    Ok((trainer, path))
}

/// Says which files the run wrote: the final model at `path`, and the best one if kept.
pub fn report(trainer: &Trainer, path: &Path) {
    println!("wrote {}", path.display());
    if let Some((step, score)) = trainer.best_quality() {
        println!(
            "wrote {} (step {step}: {score:.3} of the trivial baselines' error, validation ids)",
            trainer.best_path().display()
        );
    }
}

/// The progress bars' style (the network's training and the joint stage's fit).
pub fn progress_style() -> ProgressStyle {
    ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed_precise} < {eta_precise}]")
        .expect("valid template")
}

/// `--resume`: the run in --out from its last checkpoint.
fn resume(args: &Args) -> Result<Trainer, TrainError> {
    let model = args.model.map(ModelKind::from);
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
    Ok(trainer)
}

/// A new run in --out, of fresh weights or `--init`'s.
fn new_run(args: &Args) -> Result<Trainer, TrainError> {
    let steps = args.steps.ok_or_else(|| TrainError::Config {
        field: "steps",
        message: "missing: pass --steps N".into(),
    })?;
    // Required unless resuming (clap checks).
    let Some(data) = args.data.as_deref() else {
        return Err(TrainError::config("data", "missing: pass --data"));
    };
    let config = train_config(args, model_config(args)?, steps);
    Trainer::new_on(&args.devices, data, &args.out, config)
}

/// The network to train: `--init`'s config or the flags', without a joint stage (the config's
/// `mirror`: it would have learnt another network's reads).
fn model_config(args: &Args) -> Result<ModelConfig, TrainError> {
    let model = args.model.map(ModelKind::from);
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
    match (args.latent, model.latent) {
        (Some(asked), Some(has)) if asked != has => Err(TrainError::config(
            "latent",
            format!("--init has a latent path of {has} values, not {asked}: leave --latent out"),
        )),
        (Some(asked), _) => Ok(model.with_latent(Some(asked))),
        (None, _) => Ok(model),
    }
}

/// The model config in the header of the `--init` file.
fn init_config(path: &Path) -> Result<ModelConfig, TrainError> {
    let bytes = std::fs::read(path).map_err(|e| TrainError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    read_header(&bytes)
        .map(|header| header.config)
        .map_err(|e| TrainError::config("init", format!("{}: {e}", path.display())))
}

/// The run's settings: `model` trained for `steps` as the flags say.
fn train_config(args: &Args, model: ModelConfig, steps: u64) -> TrainConfig {
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
    config
}
