use std::fs;
use std::path::{Path, PathBuf};

use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

use crate::data::write_atomic;
use crate::model::Normalization;

use super::{TrainConfig, TrainError};

/// Run state beside the weights: enough to continue exactly where the run stopped.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckpointState {
    /// Steps completed.
    pub step: u64,
    /// The batch sampler's random stream.
    pub rng: Pcg64,
    /// The run's settings (resuming keeps them).
    pub config: TrainConfig,
    /// Joint statistics of the training split.
    pub normalization: Normalization,
    /// Best validation loss so far, and its step.
    pub best_val: Option<(u64, f32)>,
    /// Best validation quality score so far (`best.dmbn`), and its step.
    #[serde(default)]
    pub best_quality: Option<(u64, f32)>,
    /// The dataset root the run trains on, so that `--resume` needs no `--data` (none in
    /// checkpoints written before it was recorded).
    #[serde(default)]
    pub data: Option<PathBuf>,
}

/// A checkpoint folder: `model.dmbn` (model file, f32), `optimizer.bpk` (Adam state),
/// `state.json`. Written as `checkpoint.tmp/` and swapped in by renames, so a crash at any
/// point leaves a complete checkpoint (`checkpoint/`, or `checkpoint.old/` mid-swap).
pub struct Checkpoint;

impl Checkpoint {
    /// The checkpoint folder of a run's output folder.
    pub fn dir(out: &Path) -> PathBuf {
        out.join("checkpoint")
    }

    /// Write a checkpoint of `model_bytes` / `optimizer_bytes` / `state` under `out`.
    pub fn write(
        out: &Path,
        model_bytes: &[u8],
        optimizer_bytes: &[u8],
        state: &CheckpointState,
    ) -> Result<(), TrainError> {
        let dir = Self::dir(out);
        let tmp = out.join("checkpoint.tmp");
        let old = out.join("checkpoint.old");
        if tmp.exists() {
            fs::remove_dir_all(&tmp).map_err(TrainError::io(&tmp))?;
        }
        fs::create_dir_all(&tmp).map_err(TrainError::io(&tmp))?;
        write_atomic(&tmp.join("model.dmbn"), model_bytes)?;
        write_atomic(&tmp.join("optimizer.bpk"), optimizer_bytes)?;
        let json = serde_json::to_vec_pretty(state).expect("state serialises");
        write_atomic(&tmp.join("state.json"), &json)?;
        if dir.exists() {
            if old.exists() {
                fs::remove_dir_all(&old).map_err(TrainError::io(&old))?;
            }
            fs::rename(&dir, &old).map_err(TrainError::io(&dir))?;
        }
        fs::rename(&tmp, &dir).map_err(TrainError::io(&tmp))?;
        if old.exists() {
            fs::remove_dir_all(&old).map_err(TrainError::io(&old))?;
        }
        Ok(())
    }

    /// Read the newest complete checkpoint under `out`: (model bytes, optimizer bytes, state).
    pub fn read(out: &Path) -> Result<(Vec<u8>, Vec<u8>, CheckpointState), TrainError> {
        let mut dir = Self::dir(out);
        if !dir.join("state.json").exists() {
            dir = out.join("checkpoint.old");
        }
        let bad = |message: String| TrainError::Checkpoint {
            path: dir.clone(),
            message,
        };
        if !dir.join("state.json").exists() {
            return Err(TrainError::Checkpoint {
                path: Self::dir(out),
                message: "no checkpoint to resume from (run without --resume first)".into(),
            });
        }
        let read = |name: &str| fs::read(dir.join(name)).map_err(|e| bad(format!("{name}: {e}")));
        let json = read("state.json")?;
        let state = serde_json::from_slice(&json)
            .and_then(|mut state: CheckpointState| {
                upgrade(&mut state.config, &json)?;
                Ok(state)
            })
            .map_err(|e| bad(format!("state.json: {e}")))?;
        Ok((read("model.dmbn")?, read("optimizer.bpk")?, state))
    }
}

/// Settings of a `state.json` written before the run's settings held the whole model config:
/// `"model": "pte"` (read as `ModelConfig::new(kind)`) beside these three.
#[derive(Deserialize)]
struct Legacy {
    config: LegacyModel,
}

#[derive(Deserialize)]
struct LegacyModel {
    image_size: Option<usize>,
    sigma_floor: Option<f64>,
    joint_weight: Option<f64>,
}

/// Moves the model settings of such a `state.json` into `config.model`, so that those runs
/// still resume as they were.
fn upgrade(config: &mut TrainConfig, json: &[u8]) -> Result<(), serde_json::Error> {
    let Legacy { config: legacy } = serde_json::from_slice(json)?;
    let model = &mut config.model;
    model.image_size = legacy.image_size.unwrap_or(model.image_size);
    model.sigma_floor = legacy.sigma_floor.unwrap_or(model.sigma_floor);
    model.joint_weight = legacy.joint_weight.unwrap_or(model.joint_weight);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ModelKind;

    #[test]
    fn settings_written_before_the_model_config_moved_in_still_read() {
        let legacy = serde_json::json!({
            "model": "attn", "image_size": 64, "seed": 1, "steps": 3000, "batch": 8,
            "max_contexts": 5, "targets_per_sequence": 8, "lr": 0.001,
            "schedule": { "kind": "cosine", "final_fraction": 0.05 }, "clip_norm": 1.0,
            "joint_weight": 1.0, "sigma_floor": 0.02, "val_fraction": 0.1, "val_every": 250,
            "val_batches": 8, "checkpoint_every": 250
        });
        let read = |config: &serde_json::Value| {
            let json = serde_json::to_vec(&serde_json::json!({ "config": config })).unwrap();
            let mut read: TrainConfig = serde_json::from_value(config.clone()).unwrap();
            upgrade(&mut read, &json).unwrap();
            read
        };
        let config = read(&legacy);
        assert_eq!(config.model.kind, ModelKind::Attn);
        assert_eq!(
            (
                config.model.joint_weight,
                config.model.sigma_floor,
                config.model.hidden
            ),
            (1.0, 0.02, 128)
        );
        assert_eq!((config.steps, config.targets_per_sequence), (3000, 8));
        // Today's layout reads as it was written.
        let mut today = config.clone();
        today.model.joint_weight = 0.5;
        assert_eq!(read(&serde_json::to_value(&today).unwrap()), today);
    }
}
