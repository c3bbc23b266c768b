use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use super::{write_sequence, DataError, Sequence};

/// Writes a whole dataset into the temporary sibling `<out>.tmp-<pid>` and renames it to
/// `<out>` in [`finish`](Self::finish), so an interrupted run never leaves a half dataset at
/// `<out>`. Dropping an unfinished writer removes the temporary folder.
#[derive(Debug)]
pub struct DatasetWriter {
    out: PathBuf,
    tmp: PathBuf,
    written: usize,
    finished: bool,
}

impl DatasetWriter {
    /// Start a dataset at `out`, which must not exist or be an empty directory.
    pub fn create(out: impl AsRef<Path>) -> Result<Self, DataError> {
        let out = out.as_ref().to_path_buf();
        let name = out
            .file_name()
            .ok_or_else(|| DataError::OutputName { path: out.clone() })?;
        let tmp = out.with_file_name(format!(
            "{}.tmp-{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        check_output(&out)?;
        if tmp.symlink_metadata().is_ok() {
            return Err(DataError::TempExists { path: tmp });
        }
        fs::create_dir_all(&tmp).map_err(DataError::io(&tmp))?;
        Ok(DatasetWriter {
            out,
            tmp,
            written: 0,
            finished: false,
        })
    }

    /// Add sequence `id` of `action` (see [`write_sequence`]).
    pub fn write(&mut self, id: u32, action: &str, seq: &Sequence) -> Result<(), DataError> {
        write_sequence(&self.tmp, id, action, seq)?;
        self.written += 1;
        Ok(())
    }

    /// Sequences written so far.
    pub fn written(&self) -> usize {
        self.written
    }

    /// Where the dataset is being written until `finish`.
    pub fn temp_dir(&self) -> &Path {
        &self.tmp
    }

    /// Where the dataset will be once finished.
    pub fn out_dir(&self) -> &Path {
        &self.out
    }

    /// Move the dataset to its final place (checking again that nothing appeared there).
    pub fn finish(mut self) -> Result<PathBuf, DataError> {
        check_output(&self.out)?;
        if self.out.is_dir() {
            fs::remove_dir(&self.out).map_err(DataError::io(&self.out))?;
        }
        fs::rename(&self.tmp, &self.out).map_err(DataError::io(&self.out))?;
        self.finished = true;
        Ok(self.out.clone())
    }
}

impl Drop for DatasetWriter {
    fn drop(&mut self) {
        if !self.finished {
            let _ = fs::remove_dir_all(&self.tmp);
        }
    }
}

/// `out` must be absent or an empty directory.
fn check_output(out: &Path) -> Result<(), DataError> {
    match fs::symlink_metadata(out) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(DataError::Io {
            path: out.to_path_buf(),
            source,
        }),
        Ok(meta) if meta.is_dir() => {
            let mut entries = fs::read_dir(out).map_err(DataError::io(out))?;
            if entries.next().is_some() {
                Err(DataError::OutputExists {
                    path: out.to_path_buf(),
                })
            } else {
                Ok(())
            }
        }
        Ok(_) => Err(DataError::OutputExists {
            path: out.to_path_buf(),
        }),
    }
}
