use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{TrainError, ValQuality};

/// One line of `metrics.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Steps completed.
    pub step: u64,
    /// Learning rate of the last step.
    pub lr: f64,
    /// Training loss (total NLL) of the last step and its parts.
    pub loss: f32,
    pub image_nll: f32,
    pub joint_nll: f32,
    pub image_mse: f32,
    pub joint_mse: f32,
    /// A model with a latent path: KL(posterior ‖ prior) of z per sequence, nats.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub kl: Option<f32>,
    /// Validation losses, on the lines where validation ran.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_loss: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_image_mse: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_joint_mse: Option<f32>,
    /// Validation on reconstructing the contexts themselves (targets = contexts): the loss,
    /// image and joint MSE. A CNP that underfits its contexts shows it here first.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_context_loss: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_context_image_mse: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_context_joint_mse: Option<f32>,
    /// The quality benchmark on held-out sequences (model over baseline, per scenario and
    /// modality), where it ran.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub val_quality: Option<ValQuality>,
    /// Optimiser steps per second over the last logging interval.
    pub steps_per_s: f64,
}

/// Append-only JSON-lines log of a run.
pub struct MetricsLog {
    path: PathBuf,
    file: File,
}

impl MetricsLog {
    /// Open (create) the log; on resume, drop the lines past `keep_through` first so the log
    /// reads as one uninterrupted run.
    pub fn open(path: &Path, keep_through: Option<u64>) -> Result<MetricsLog, TrainError> {
        if let Some(step) = keep_through {
            let kept: Vec<String> = match File::open(path) {
                Ok(f) => BufReader::new(f)
                    .lines()
                    .map_while(Result::ok)
                    .filter(|line| {
                        serde_json::from_str::<Metrics>(line).is_ok_and(|m| m.step <= step)
                    })
                    .collect(),
                Err(_) => Vec::new(),
            };
            let mut text = kept.join("\n");
            if !text.is_empty() {
                text.push('\n');
            }
            crate::data::write_atomic(path, text.as_bytes())?;
        }
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(TrainError::io(path))?;
        Ok(MetricsLog {
            path: path.to_path_buf(),
            file,
        })
    }

    /// Append one line.
    pub fn write(&mut self, m: &Metrics) -> Result<(), TrainError> {
        let line = serde_json::to_string(m).expect("metrics serialise");
        writeln!(self.file, "{line}").map_err(TrainError::io(&self.path))
    }
}
