use std::path::PathBuf;

use thiserror::Error;

/// Drawing or writing a figure failed.
#[derive(Debug, Error)]
pub enum FigureError {
    #[error("figure: {0}")]
    Draw(String),
    #[error("figure: {what}: {reason}")]
    Input { what: &'static str, reason: String },
    #[error("{}: {reason}", path.display())]
    Write { path: PathBuf, reason: String },
}
