use std::path::PathBuf;

use thiserror::Error;

use crate::data::DataError;
use crate::model::ModelError;

/// What can stop a training run.
#[derive(Debug, Error)]
pub enum TrainError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("invalid setting {field}: {message}")]
    Config {
        field: &'static str,
        message: String,
    },
    #[error("training batches: {message}")]
    Batches { message: String },
    #[error("{path}: checkpoint is unreadable: {message}")]
    Checkpoint { path: PathBuf, message: String },
    #[error(
        "loss became {value} at step {step}: training stopped; the last good checkpoint is kept \
         (try a lower --lr or a larger σ floor)"
    )]
    NonFinite { step: u64, value: f32 },
}

impl TrainError {
    pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> TrainError {
        let path = path.into();
        move |e| TrainError::Io {
            path,
            message: e.to_string(),
        }
    }

    /// A bad or missing setting `field`.
    pub fn config(field: &'static str, message: impl Into<String>) -> TrainError {
        TrainError::Config {
            field,
            message: message.into(),
        }
    }
}
