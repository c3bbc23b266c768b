use std::io;
use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong reading or writing a dataset. Every message names the file (and line,
/// column or field where there is one) and what was expected, so a bad dataset can be fixed
/// from the message alone.
#[derive(Debug, Error)]
pub enum DataError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{}: no such file", path.display())]
    MissingFile { path: PathBuf },
    #[error(
        "{}: frame {index} is missing: expected {index}.png or {index}.jpeg, one frame per joint row ({missing} of {rows} missing)",
        dir.display()
    )]
    MissingFrame {
        dir: PathBuf,
        /// The first missing step.
        index: usize,
        /// How many of the steps have no frame.
        missing: usize,
        rows: usize,
    },
    #[error("{}: no sequence {id}/{action}: the dataset holds ids {ids} with actions {actions}", root.display())]
    UnknownSequence {
        root: PathBuf,
        id: u32,
        action: String,
        ids: String,
        actions: String,
    },
    #[error("{}: cannot decode frame: {source}", path.display())]
    CorruptFrame {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error(
        "{}: expected a {}x{} frame (as the sequence's first), found {}x{}",
        path.display(), expected.0, expected.1, found.0, found.1
    )]
    FrameSize {
        path: PathBuf,
        expected: (u32, u32),
        found: (u32, u32),
    },
    #[error(
        "{}: {found} joint values a step, expected {expected} as in {} (every sequence of a dataset, and the model, has the same joints)",
        path.display(), reference
    )]
    JointWidth {
        path: PathBuf,
        found: usize,
        expected: usize,
        reference: String,
    },
    #[error("{}: no {what} (expected {}): {needed_by} needs it", dir.display(), file.display())]
    Missing {
        dir: PathBuf,
        what: &'static str,
        file: PathBuf,
        needed_by: &'static str,
    },
    #[error("{}: {reason}", path.display())]
    Metadata { path: PathBuf, reason: String },
    #[error("{}: cannot encode frame as PNG: {source}", path.display())]
    Encode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("{} line {line}: expected {expected} columns, found {found}", path.display())]
    Columns {
        path: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("{} line {line} column {column}: expected a finite number, found {text:?}", path.display())]
    NonNumeric {
        path: PathBuf,
        line: usize,
        column: usize,
        text: String,
    },
    #[error("{}: no rows: expected at least one step", path.display())]
    NoRows { path: PathBuf },
    #[error("{}: {found} rows, expected {expected} as in {}", path.display(), reference.display())]
    RowMismatch {
        path: PathBuf,
        found: usize,
        expected: usize,
        reference: PathBuf,
    },
    #[error(
        "{}: no sequences found: expected numeric id folders holding action folders (grasp/, move/)",
        path.display()
    )]
    NoSequences { path: PathBuf },
    #[error("{}: id folder holds no action folder: expected grasp/ and/or move/", path.display())]
    NoActions { path: PathBuf },
    #[error("{}: not a directory", path.display())]
    NotADirectory { path: PathBuf },
    #[error(
        "{}: already exists and is not an empty directory: refusing to write a dataset over it",
        path.display()
    )]
    OutputExists { path: PathBuf },
    #[error(
        "{}: a temporary folder of this name already exists (left by an interrupted run?): remove it",
        path.display()
    )]
    TempExists { path: PathBuf },
    #[error("{}: the output path has no folder name", path.display())]
    OutputName { path: PathBuf },
    #[error("image size {size} is not supported: expected 1 to {max} pixels", max = crate::data::MAX_IMAGE_SIZE)]
    ImageSize { size: u32 },
    #[error("action folder name {name:?} is not valid: expected a plain name such as \"grasp\"")]
    ActionName { name: String },
    #[error("sequence {id} ({action}) cannot be written: {reason}")]
    InvalidSequence {
        id: u32,
        action: String,
        reason: String,
    },
}

impl DataError {
    /// Wrap an io error with the path it happened on.
    pub(crate) fn io(path: impl Into<PathBuf>) -> impl FnOnce(io::Error) -> DataError {
        let path = path.into();
        move |source| DataError::Io { path, source }
    }
}
