#[cfg(not(target_arch = "wasm32"))]
use std::io;
#[cfg(not(target_arch = "wasm32"))]
use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong building a model, feeding it a batch or reading a model file. Every
/// message names the field (or file) and what was expected, so bad input can be fixed from the
/// message alone; nothing in `model/` panics on bad input.
#[derive(Debug, Error)]
pub enum ModelError {
    #[error("model config: `{field}` {reason}")]
    Config { field: &'static str, reason: String },
    #[error("batch: `{field}` must be at least 1, found 0")]
    EmptyDimension { field: &'static str },
    #[error("batch: `{field}` holds {found} values, expected {expected} ({shape})")]
    Length {
        field: &'static str,
        expected: usize,
        found: usize,
        shape: String,
    },
    #[error("batch: `{field}`[{index}] is {value}: expected a finite number")]
    NotFinite {
        field: &'static str,
        index: usize,
        value: f32,
    },
    #[error("batch: `context_mask`[{index}] is {value}: expected 0 (padding) or 1 (context)")]
    MaskValue { index: usize, value: f32 },
    #[error("batch: sequence {sequence} has no context: expected at least one 1 in its `context_mask` row")]
    EmptyContext { sequence: usize },
    #[error("batch: `blend`[{sequence}] is {value}: expected a coefficient in [0, 1]")]
    Blend { sequence: usize, value: f32 },
    #[error("batch: `{field}` is empty: the loss needs target frames and joints")]
    MissingTargets { field: &'static str },
    #[error("observations: `{field}` {reason}")]
    Observation { field: &'static str, reason: String },
    #[error("batch: frames are {found}x{found}, but the model expects {expected}x{expected}")]
    ImageSize { expected: usize, found: usize },
    #[error("joints: the data has {found} joint values a step, but the model was trained on {expected}: use a model trained on this robot's data")]
    JointCount { expected: usize, found: usize },
    #[error("encoded contexts: {0}")]
    Contexts(String),
    #[error("decode: `target_times` is {found:?}, expected [{batch}, M] with M >= 1 for a representation of {batch} sequences")]
    TargetTimes { batch: usize, found: [usize; 2] },
    #[error("normalization: `{field}`[{index}] is {value}: expected {expected}")]
    Normalization {
        field: &'static str,
        index: usize,
        value: f32,
        expected: &'static str,
    },
    #[error("model file: truncated: {what} needs {expected} bytes, only {found} left")]
    Truncated {
        what: &'static str,
        expected: usize,
        found: usize,
    },
    #[error("model file: not a dmbn model file (the first 8 bytes are not \"DMBNMODL\")")]
    NotAModelFile,
    #[error(
        "model file: format version {found} is not supported: this build reads version {supported}"
    )]
    Version { found: u32, supported: u32 },
    #[error("model file: bad header: {0}")]
    Header(String),
    #[error("model file: {found} unexpected bytes after the weights")]
    TrailingBytes { found: usize },
    #[error("model file: the weights are corrupt: their SHA-256 does not match the header's")]
    Checksum,
    #[error("model file: holds a {found} model, expected {expected}")]
    Kind { expected: String, found: String },
    #[error(
        "model file: holds a model for {found}x{found} frames, expected {expected}x{expected}"
    )]
    FileImageSize { expected: usize, found: usize },
    #[error("model file: the weights do not match the header's config: {0}")]
    Weights(String),
    #[error("safetensors: {0}")]
    Safetensors(String),
    #[cfg(not(target_arch = "wasm32"))]
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A model file read from a path: which one (`dmbn probe` reads two).
    #[cfg(not(target_arch = "wasm32"))]
    #[error("{}: {source}", path.display())]
    InFile {
        path: PathBuf,
        #[source]
        source: Box<ModelError>,
    },
}

impl ModelError {
    /// A config field with a bad value.
    pub(crate) fn config(field: &'static str, reason: impl Into<String>) -> Self {
        ModelError::Config {
            field,
            reason: reason.into(),
        }
    }

    /// Bad inference input (observations or target times).
    pub(crate) fn observation(field: &'static str, reason: impl Into<String>) -> Self {
        ModelError::Observation {
            field,
            reason: reason.into(),
        }
    }

    /// Wrap the error of reading the model file at `path` with that path (an io error already
    /// has it).
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn in_file(path: impl Into<PathBuf>) -> impl FnOnce(ModelError) -> ModelError {
        let path = path.into();
        move |source| match source {
            ModelError::Io { .. } => source,
            source => ModelError::InFile {
                path,
                source: Box::new(source),
            },
        }
    }

    /// Wrap an io error with the path it happened on.
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(io::Error) -> ModelError {
        let path = path.into();
        move |source| ModelError::Io { path, source }
    }
}
