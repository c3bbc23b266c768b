//! The one way the project writes a file: datasets, checkpoints and model files alike.
use std::fs;
use std::io::Write;
use std::path::Path;

use super::DataError;

/// Writes `bytes` to `path` through a hidden temporary sibling, flushed to the disk, then a
/// rename: a reader sees the old file or the whole new one, even after a crash, never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), DataError> {
    let name = path
        .file_name()
        .ok_or_else(|| DataError::OutputName {
            path: path.to_path_buf(),
        })?
        .to_string_lossy();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()
    };
    let result = write()
        .map_err(DataError::io(&tmp))
        .and_then(|()| fs::rename(&tmp, path).map_err(DataError::io(path)));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}
