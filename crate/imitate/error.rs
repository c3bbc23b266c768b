use thiserror::Error;

use crate::model::ModelError;
use crate::sim::SimError;

/// What can go wrong when a model imitates a demonstration.
#[derive(Debug, Error)]
pub enum ImitateError {
    /// The model could not predict (bad observations, a foreign file).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The arm could not perform (a bad trajectory, an object outside the table's region).
    #[error(transparent)]
    Sim(#[from] SimError),
    /// Something about the demonstration or the request.
    #[error("{0}")]
    Invalid(String),
}
