use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io;
use std::path::{Component, Path, PathBuf};

use super::{DataError, Files};

/// A folder tree held in memory: what the page has of the folder the user chose. Every file is
/// known by its relative path (`data2020/0/grasp/joint_0.txt`, as the browser names it), so
/// the dataset can be listed at once; only the files of a sequence about to be read need their
/// bytes ([`put`](Self::put)), so a whole dataset never has to be in memory.
#[derive(Debug, Clone, Default)]
pub struct MemoryFiles {
    /// Path → bytes, `None` until handed over.
    files: BTreeMap<PathBuf, Option<Vec<u8>>>,
}

impl MemoryFiles {
    /// A tree of the files `paths` (`/`-separated, relative; empty, `.` and `..` parts dropped),
    /// none of whose bytes are here yet.
    pub fn new<S: AsRef<str>>(paths: impl IntoIterator<Item = S>) -> Self {
        let files = paths
            .into_iter()
            .map(|p| (clean(p.as_ref()), None))
            .filter(|(p, _)| p.components().next().is_some())
            .collect();
        MemoryFiles { files }
    }

    /// Hands over the bytes of file `path` (added to the tree if it was not listed).
    pub fn put(&mut self, path: &str, bytes: Vec<u8>) {
        self.files.insert(clean(path), Some(bytes));
    }

    /// True when `path` is one of the tree's files.
    pub fn contains(&self, path: &str) -> bool {
        self.files.contains_key(&clean(path))
    }

    /// Drops every file's bytes (the tree stays): after a sequence has been read.
    pub fn release(&mut self) {
        self.files.values_mut().for_each(|b| *b = None);
    }

    /// Number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// True when the tree holds no file.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The first part of each path below `dir` that has at least `depth` more parts: the
    /// entries of `dir` that are folders (`depth` 2) or files (exactly 1).
    fn children(&self, dir: &Path, folders: bool) -> Vec<String> {
        let mut out: Vec<String> = self
            .files
            .keys()
            .filter_map(|p| p.strip_prefix(dir).ok())
            .filter(|rest| (rest.components().count() > 1) == folders)
            .filter_map(|rest| rest.components().next())
            .filter_map(|c| c.as_os_str().to_str().map(str::to_string))
            .collect();
        out.dedup();
        out
    }
}

/// `a/b/../c` as path parts, without empty, `.` or `..` ones (a browser never sends them).
fn clean(path: &str) -> PathBuf {
    Path::new(path)
        .components()
        .filter(|c| matches!(c, Component::Normal(_)))
        .collect()
}

impl Files for MemoryFiles {
    fn is_dir(&self, path: &Path) -> Result<bool, DataError> {
        if self.files.contains_key(path) {
            Ok(false)
        } else if self.files.keys().any(|p| p.starts_with(path)) {
            Ok(true)
        } else {
            Err(DataError::MissingFile {
                path: path.to_path_buf(),
            })
        }
    }

    fn folders(&self, dir: &Path) -> Result<Vec<String>, DataError> {
        Ok(self.children(dir, true))
    }

    fn files(&self, dir: &Path) -> Result<Vec<String>, DataError> {
        Ok(self.children(dir, false))
    }

    fn read(&self, path: &Path) -> Result<Cow<'_, [u8]>, DataError> {
        match self.files.get(path) {
            Some(Some(bytes)) => Ok(Cow::Borrowed(bytes)),
            Some(None) => Err(DataError::Io {
                path: path.to_path_buf(),
                source: io::Error::other("its bytes were not handed over"),
            }),
            None => Err(DataError::MissingFile {
                path: path.to_path_buf(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_folders_and_files() {
        let mut m = MemoryFiles::new([
            "d/0/grasp/0.png",
            "d/0/grasp/joint_0.txt",
            "d/LICENSE",
            "d/1/move/x",
        ]);
        let mut folders = m.folders(Path::new("d")).unwrap();
        folders.sort();
        assert_eq!(folders, ["0", "1"]);
        assert_eq!(m.files(Path::new("d")).unwrap(), ["LICENSE"]);
        assert!(m.is_dir(Path::new("d/0")).unwrap());
        assert!(!m.is_dir(Path::new("d/LICENSE")).unwrap());
        assert!(m.is_dir(Path::new("e")).is_err());
        assert!(m.read(Path::new("d/LICENSE")).is_err());
        m.put("d/LICENSE", b"MIT".to_vec());
        assert_eq!(&*m.read(Path::new("d/LICENSE")).unwrap(), b"MIT");
        m.release();
        assert!(m.read(Path::new("d/LICENSE")).is_err());
    }
}
