use std::path::{Path, PathBuf};

use super::layout::valid_action_name;
use super::{read_sequence_from, DataError, Disk, Files, Sequence, SequenceRef};

/// A dataset in the DMBN layout: `<root>/<id>/<action>/` folders. Opening only lists the
/// sequences; reading (and validating) each is [`read`](Self::read)'s job.
#[derive(Debug, Clone)]
pub struct Dataset {
    root: PathBuf,
    sequences: Vec<SequenceRef>,
}

impl Dataset {
    /// List the sequences under `root`: every folder with a decimal name is an id, every
    /// non-hidden folder inside it an action. Other entries (a LICENSE file, hidden folders)
    /// are ignored. Sequences are sorted by id, then action name.
    pub fn open(root: impl AsRef<Path>) -> Result<Self, DataError> {
        Self::list(&Disk, root)
    }

    /// [`open`](Self::open) on any [`Files`]: the same listing and errors for a folder held
    /// in memory (the page's). Read its sequences with [`read_sequence_from`] and the same files.
    pub fn list(files: &impl Files, root: impl AsRef<Path>) -> Result<Self, DataError> {
        let root = root.as_ref().to_path_buf();
        if !files.is_dir(&root)? {
            return Err(DataError::NotADirectory { path: root });
        }
        let mut sequences = Vec::new();
        for id in files.folders(&root)? {
            let id_dir = root.join(&id);
            let Some(id) = parse_id(&id) else { continue };
            let mut actions: Vec<SequenceRef> = files
                .folders(&id_dir)?
                .into_iter()
                .filter(|name| valid_action_name(name))
                .map(|action| SequenceRef {
                    id,
                    dir: id_dir.join(&action),
                    action,
                })
                .collect();
            if actions.is_empty() {
                return Err(DataError::NoActions { path: id_dir });
            }
            sequences.append(&mut actions);
        }
        if sequences.is_empty() {
            return Err(DataError::NoSequences { path: root });
        }
        sequences.sort_by(|a, b| (a.id, &a.action).cmp(&(b.id, &b.action)));
        Ok(Dataset { root, sequences })
    }

    /// The folder the dataset was opened from.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Every sequence, by id then action.
    pub fn sequences(&self) -> &[SequenceRef] {
        &self.sequences
    }

    /// Number of sequences (all actions).
    pub fn len(&self) -> usize {
        self.sequences.len()
    }

    /// Never true for an opened dataset; here for API symmetry with `len`.
    pub fn is_empty(&self) -> bool {
        self.sequences.is_empty()
    }

    /// Distinct ids, ascending.
    pub fn ids(&self) -> Vec<u32> {
        let mut ids: Vec<u32> = self.sequences.iter().map(|s| s.id).collect();
        ids.dedup();
        ids
    }

    /// Distinct action names, sorted.
    pub fn actions(&self) -> Vec<String> {
        let mut actions: Vec<String> = self.sequences.iter().map(|s| s.action.clone()).collect();
        actions.sort();
        actions.dedup();
        actions
    }

    /// The sequence `id`/`action`, or an error listing what the dataset holds.
    pub fn find(&self, id: u32, action: &str) -> Result<&SequenceRef, DataError> {
        self.sequences
            .iter()
            .find(|s| s.id == id && s.action == action)
            .ok_or_else(|| DataError::UnknownSequence {
                root: self.root.clone(),
                id,
                action: action.to_string(),
                ids: format!(
                    "{}..={}",
                    self.ids().first().copied().unwrap_or(0),
                    self.ids().last().copied().unwrap_or(0)
                ),
                actions: self.actions().join(", "),
            })
    }

    /// Read and validate one sequence; frames resized to `image_size` when given.
    pub fn read(&self, seq: &SequenceRef, image_size: Option<u32>) -> Result<Sequence, DataError> {
        read_sequence_from(&Disk, &seq.dir, seq.id, image_size)
    }
}

/// A decimal id folder name (`"7"`, `"40"`); anything else is not an id.
fn parse_id(name: &str) -> Option<u32> {
    if name.is_empty() || !name.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    name.parse().ok()
}
