//! The one error every command returns.
use std::path::PathBuf;

use thiserror::Error;

use dmbn::data::DataError;
use dmbn::figure::FigureError;
use dmbn::model::ModelError;
use dmbn::sim::SimError;
use dmbn::train::TrainError;

/// Everything a command can fail with; printed as `error: <message>`.
#[derive(Debug, Error)]
pub enum CliError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error(transparent)]
    Sim(#[from] SimError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Figure(#[from] FigureError),
    #[error(transparent)]
    Train(#[from] TrainError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{0}")]
    Usage(String),
}
