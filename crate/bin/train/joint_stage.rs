//! `--joint-stage`: fitting the joint stage to a model file's network, after training or
//! (`--init FILE --steps 0`) to FILE's as it is.
use std::path::Path;

use indicatif::ProgressBar;

use dmbn::data::write_atomic;
use dmbn::train::{add_joint_stage, JointStageFit, JointStageProgress, Split, TrainError, Trainer};

use crate::args::Args;
use crate::train::progress_style;

/// The `--joint-stage-*` flags' fit.
pub fn settings(args: &Args) -> JointStageFit {
    JointStageFit {
        width: args.joint_stage_width,
        draws: args.joint_stage_draws,
        steps: args.joint_stage_steps,
        seed: args.seed,
        ..JointStageFit::default()
    }
}

/// `--init FILE --steps 0 --joint-stage`: FILE as it is (its network, normalisation and σ
/// scales) with a joint stage, as --out/model.dmbn.
pub fn add_to_init_file(args: &Args) -> Result<(), TrainError> {
    let init = args.init.as_deref().ok_or_else(|| {
        TrainError::config(
            "init",
            "missing: --steps 0 --joint-stage fits a joint stage to a model file's network: pass --init FILE",
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
    fit(args, &split, args.camera.as_deref(), &path)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `--joint-stage` after training: a stage for the network `trainer` wrote to `path`, fitted
/// on the run's own split of its data.
pub fn add_after_training(args: &Args, trainer: &Trainer, path: &Path) -> Result<(), TrainError> {
    let data = trainer
        .data()
        .ok_or_else(|| TrainError::config("data", "missing: pass --data"))?;
    let config = trainer.config();
    let split = Split::open_camera(data, config.val_fraction, config.camera.as_deref())?;
    fit(args, &split, config.camera.as_deref(), path)
}

/// The joint stage fitted to the model file at `path` (rewritten with it), on the CPU.
fn fit(args: &Args, split: &Split, camera: Option<&str>, path: &Path) -> Result<(), TrainError> {
    let fit = settings(args);
    eprintln!(
        "fitting the joint stage: {} training and {} validation sequences, {} layouts each",
        split.train.len(),
        split.val.len(),
        fit.draws
    );
    let bar = ProgressBar::new(0);
    bar.set_style(progress_style());
    let started = std::time::Instant::now();
    let val = if split.validates_on_training_data() {
        &[][..]
    } else {
        &split.val[..]
    };
    add_joint_stage(
        path,
        &split.train,
        val,
        camera,
        fit,
        &burn::tensor::Device::flex().autodiff(),
        |stage| match stage {
            JointStageProgress::Reading { done, total } => {
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
            JointStageProgress::Fitting(p) => {
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
                            "joint stage step {}/{}: {message} ({:.0?})",
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
