use thiserror::Error;

/// What is wrong with an augmentation setting or an evaluation mode.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum AugmentError {
    /// A [`TimeWarpConfig`](super::TimeWarpConfig) field out of its range.
    #[error("{field} is {value}: expected {expected}")]
    TimeWarp {
        field: &'static str,
        value: String,
        expected: String,
    },
    /// Not one of the paper's evaluation modes.
    #[error("{found:?} is not a mode: expected t, p or f")]
    Mode { found: String },
}
