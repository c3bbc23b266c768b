use std::path::Path;

use crate::data::{Dataset, Disk, SequenceRef};

use super::TrainError;

/// Training and validation sequences of a dataset, split by sequence id so both actions of
/// one id land on the same side: the last `val_fraction` of the ids (at least one when there
/// are two or more) are held out. `val_fraction` 0, or a dataset of one id, holds none out:
/// the validation loss then measures training sequences ([`Split::validates_on_training_data`])
/// and the quality benchmark (best.dmbn) does not run. Only listed: reading is the caller's
/// (training streams its sequences' frames, the probe reads them whole).
pub struct Split {
    pub train: Vec<SequenceRef>,
    pub val: Vec<SequenceRef>,
    /// Held-out ids.
    pub val_ids: Vec<u32>,
    /// The dataset's joint values a step (its first sequence's) and their names, where its
    /// `dataset.json` gives them.
    pub joints: (usize, Option<Vec<String>>),
}

impl Split {
    /// List the sequences of the dataset at `root` and split them.
    pub fn open(root: &Path, val_fraction: f64) -> Result<Split, TrainError> {
        Self::open_camera(root, val_fraction, None)
    }

    /// [`Split::open`], checking that the sequences have `camera`'s frames (a sub-folder of
    /// each sequence's; `None`: the default camera).
    pub fn open_camera(
        root: &Path,
        val_fraction: f64,
        camera: Option<&str>,
    ) -> Result<Split, TrainError> {
        if !(0.0..1.0).contains(&val_fraction) {
            return Err(TrainError::config(
                "val_fraction",
                format!("{val_fraction}: expected a value in [0, 1)"),
            ));
        }
        let dataset = Dataset::open(root)?.with_camera(&Disk, camera)?;
        let joints = dataset.joint_width(&Disk)?;
        let ids = dataset.ids();
        let held = if ids.len() < 2 || val_fraction == 0.0 {
            0
        } else {
            ((ids.len() as f64 * val_fraction).ceil() as usize).max(1)
        };
        let val_ids = ids[ids.len() - held..].to_vec();
        let (val, train): (Vec<SequenceRef>, Vec<SequenceRef>) = dataset
            .sequences()
            .iter()
            .cloned()
            .partition(|s| val_ids.contains(&s.id));
        if train.is_empty() {
            return Err(TrainError::config(
                "data",
                format!("{}: no training sequences", root.display()),
            ));
        }
        Ok(Split {
            train,
            val,
            val_ids,
            joints,
        })
    }

    /// True when no id is held out, so that validation (the loss and `best.dmbn`) can only
    /// measure the training sequences themselves.
    pub fn validates_on_training_data(&self) -> bool {
        self.val_ids.is_empty()
    }
}
