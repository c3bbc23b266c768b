//! Where a dataset's files come from: the disk (the tools) or memory (the page, which is handed
//! the files of a folder the user chose). The listing and the reader see only [`Files`], so the
//! native tools and the page validate alike and report the same errors.
use std::borrow::Cow;
use std::fs;
use std::io;
use std::path::Path;

use super::DataError;

/// A folder tree's files, by path.
pub trait Files {
    /// Whether `path` is a folder (`false` for a file); an error naming it when it is neither.
    fn is_dir(&self, path: &Path) -> Result<bool, DataError>;
    /// Names of the folders in `dir` (UTF-8 names only), in no particular order.
    fn folders(&self, dir: &Path) -> Result<Vec<String>, DataError>;
    /// Names of the files in `dir` (UTF-8 names only), in no particular order.
    fn files(&self, dir: &Path) -> Result<Vec<String>, DataError>;
    /// The bytes of the file `path`.
    fn read(&self, path: &Path) -> Result<Cow<'_, [u8]>, DataError>;
}

/// The file system: paths as the tools are given them.
#[derive(Debug, Clone, Copy, Default)]
pub struct Disk;

impl Disk {
    /// UTF-8 names of the entries of `dir` that are (`want_dir`) or are not folders.
    fn entries(dir: &Path, want_dir: bool) -> Result<Vec<String>, DataError> {
        let mut out = Vec::new();
        for entry in fs::read_dir(dir).map_err(io_error(dir))? {
            let entry = entry.map_err(io_error(dir))?;
            if entry.path().is_dir() != want_dir {
                continue;
            }
            if let Ok(name) = entry.file_name().into_string() {
                out.push(name);
            }
        }
        Ok(out)
    }
}

impl Files for Disk {
    fn is_dir(&self, path: &Path) -> Result<bool, DataError> {
        Ok(fs::metadata(path).map_err(io_error(path))?.is_dir())
    }

    fn folders(&self, dir: &Path) -> Result<Vec<String>, DataError> {
        Disk::entries(dir, true)
    }

    fn files(&self, dir: &Path) -> Result<Vec<String>, DataError> {
        Disk::entries(dir, false)
    }

    fn read(&self, path: &Path) -> Result<Cow<'_, [u8]>, DataError> {
        Ok(Cow::Owned(fs::read(path).map_err(io_error(path))?))
    }
}

/// An io error on `path`: a missing file is [`DataError::MissingFile`], as in memory.
fn io_error(path: &Path) -> impl FnOnce(io::Error) -> DataError + '_ {
    move |source| {
        if source.kind() == io::ErrorKind::NotFound {
            DataError::MissingFile {
                path: path.to_path_buf(),
            }
        } else {
            DataError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
    }
}
