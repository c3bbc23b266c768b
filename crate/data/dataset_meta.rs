use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{DataError, Files};

/// A dataset's optional `dataset.json` at its root: what the DMBN folders cannot say for
/// themselves. The converters (`python -m dmbn_convert`) write it; every field is optional
/// and unknown fields are ignored, so a hand-written one may say only what it knows.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DatasetMeta {
    /// A name for each joint value, in column order (saved in the model file by `train`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_names: Option<Vec<String>>,
    /// The cameras: the first is the default one (`<k>.png` in each sequence folder), every
    /// other a sub-folder of that name (`<camera>/<k>.png`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cameras: Option<Vec<String>>,
    /// Steps per second of the recording.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
    /// Where the data came from (free text).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

impl DatasetMeta {
    /// The file's name at a dataset's root.
    pub const FILE: &'static str = "dataset.json";

    /// `<root>/dataset.json`, or the default (nothing known) where there is none.
    pub fn read(files: &impl Files, root: &Path) -> Result<Self, DataError> {
        if !files.files(root)?.iter().any(|n| n == Self::FILE) {
            return Ok(Self::default());
        }
        let path = root.join(Self::FILE);
        let bytes = files.read(&path)?;
        let meta: DatasetMeta = serde_json::from_slice(&bytes).map_err(|e| DataError::Metadata {
            path: path.clone(),
            reason: format!("{e}: expected a JSON object with optional joint_names (a list of strings), cameras, fps, source"),
        })?;
        if let Some(names) = &meta.joint_names {
            if names.is_empty() || names.iter().any(|n| n.trim().is_empty()) {
                return Err(DataError::Metadata {
                    path,
                    reason: "joint_names: expected a non-empty name for every joint value".into(),
                });
            }
        }
        Ok(meta)
    }

    /// The joint names, checked against the data's `width` values a step.
    pub fn names_for(&self, root: &Path, width: usize) -> Result<Option<Vec<String>>, DataError> {
        match &self.joint_names {
            Some(names) if names.len() != width => Err(DataError::Metadata {
                path: root.join(Self::FILE),
                reason: format!(
                    "joint_names: {} names, expected {width} (the joint values a step of its sequences)",
                    names.len()
                ),
            }),
            names => Ok(names.clone()),
        }
    }
}
