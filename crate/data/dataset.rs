use std::path::{Path, PathBuf};

use super::layout::valid_action_name;
use super::{
    read_joints, read_sequence_from, DataError, DatasetMeta, Disk, Files, Sequence, SequenceRef,
};

/// A dataset in the DMBN layout: `<root>/<id>/<action>/` folders, and optionally a
/// `dataset.json` ([`DatasetMeta`]). Opening only lists the sequences; reading (and
/// validating) each is [`read`](Self::read)'s job.
#[derive(Debug, Clone)]
pub struct Dataset {
    root: PathBuf,
    sequences: Vec<SequenceRef>,
    meta: DatasetMeta,
    camera: Option<String>,
}

impl Dataset {
    /// List the sequences under `root`: every folder with a decimal name is an id, every
    /// non-hidden folder inside it an action. Other entries (a LICENSE file, hidden folders)
    /// are ignored. Sequences are sorted by id, then action name.
    pub fn open(root: impl AsRef<Path>) -> Result<Self, DataError> {
        let mut dataset = Self::list(&Disk, root)?;
        dataset.meta = DatasetMeta::read(&Disk, &dataset.root)?;
        Ok(dataset)
    }

    /// [`open`](Self::open) on any [`Files`]: the same listing and errors for a folder held
    /// in memory (the page's), without its `dataset.json` (the page names joints by the
    /// model's file). Read its sequences with [`read_sequence_from`] and the same files.
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
        Ok(Dataset {
            root,
            sequences,
            meta: DatasetMeta::default(),
            camera: None,
        })
    }

    /// Read `camera`'s frames (its sub-folder `<camera>/` in every sequence folder) instead
    /// of the default camera's; `None` keeps the default. An error names the cameras the first
    /// sequence holds when it has no such folder.
    pub fn with_camera(
        mut self,
        files: &impl Files,
        camera: Option<&str>,
    ) -> Result<Self, DataError> {
        if let Some(name) = camera {
            let first = &self.sequences[0].dir;
            let cameras = files.folders(first)?;
            if !valid_action_name(name) || !cameras.iter().any(|c| c == name) {
                let mut cameras = cameras;
                cameras.sort();
                return Err(DataError::Metadata {
                    path: first.clone(),
                    reason: format!(
                        "no camera {name:?}: expected a sub-folder of that name holding its frames; \
                         the cameras here are the default (<k>.png){}",
                        cameras.iter().map(|c| format!(", {c}")).collect::<String>()
                    ),
                });
            }
        }
        self.camera = camera.map(str::to_string);
        Ok(self)
    }

    /// The camera whose frames [`read`](Self::read) returns (`None`: the default camera).
    pub fn camera(&self) -> Option<&str> {
        self.camera.as_deref()
    }

    /// The dataset's `dataset.json` (empty where it has none).
    pub fn meta(&self) -> &DatasetMeta {
        &self.meta
    }

    /// The joint values a step of every sequence (D) and their names where `dataset.json`
    /// gives them: read from the first sequence's joint file; [`check_width`](Self::check_width)
    /// holds the others to it.
    pub fn joint_width(
        &self,
        files: &impl Files,
    ) -> Result<(usize, Option<Vec<String>>), DataError> {
        let first = &self.sequences[0];
        let width = read_joints(files, &first.dir, first.id)?.width();
        Ok((width, self.meta.names_for(&self.root, width)?))
    }

    /// An error naming `seq`'s joint file unless its `found` values a step are `expected`
    /// (the dataset's first sequence's, or a model's: `reference` says which).
    pub fn check_width(
        seq: &SequenceRef,
        found: usize,
        expected: usize,
        reference: &str,
    ) -> Result<(), DataError> {
        if found == expected {
            return Ok(());
        }
        Err(DataError::JointWidth {
            path: super::joint_path(&seq.dir, seq.id),
            found,
            expected,
            reference: reference.to_string(),
        })
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

    /// Read and validate one sequence (the chosen camera's frames); frames resized to
    /// `image_size` when given.
    pub fn read(&self, seq: &SequenceRef, image_size: Option<u32>) -> Result<Sequence, DataError> {
        read_sequence_from(&Disk, &seq.dir, seq.id, self.camera(), image_size)
    }
}

/// A decimal id folder name (`"7"`, `"40"`); anything else is not an id.
fn parse_id(name: &str) -> Option<u32> {
    if name.is_empty() || !name.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    name.parse().ok()
}
