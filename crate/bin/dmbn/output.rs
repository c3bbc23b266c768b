//! What several commands write: progress bars, folders and atomic files.
use std::fs;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::error::CliError;

/// A progress bar of `len` steps labelled `what`.
/// How a table row names the model file at `path`: its file name (the whole path without one).
pub fn model_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

pub fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// Creates `dir` and its parents.
pub fn create_dir(dir: &Path) -> Result<(), CliError> {
    fs::create_dir_all(dir).map_err(|source| CliError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `bytes` at `path` atomically.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    Ok(dmbn::data::write_atomic(path, bytes)?)
}

/// Writes `value` as pretty JSON at `path` atomically.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<(), CliError> {
    let json = serde_json::to_vec_pretty(value).map_err(|e| CliError::Usage(e.to_string()))?;
    write(path, &json)
}
