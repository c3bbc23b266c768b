//! Helpers shared by the native integration tests (`mod support;`).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The original DMBN dataset, when present: `$DMBN2020` or `../shared/datasets/dmbn2020`.
/// Tests that need it print a note and pass without it; it is never part of the repository.
pub fn dmbn2020() -> Option<PathBuf> {
    let path = std::env::var_os("DMBN2020")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/datasets/dmbn2020")
        });
    path.is_dir().then_some(path)
}

/// The original DMBN dataset opened, or `None` after printing the note that the test using it
/// passes without it.
pub fn dmbn2020_dataset() -> Option<dmbn::data::Dataset> {
    let Some(root) = dmbn2020() else {
        println!("note: dmbn2020 not found (set DMBN2020); skipping");
        return None;
    };
    Some(dmbn::data::Dataset::open(&root).unwrap())
}

/// A file of the repository's `assets/`.
pub fn asset(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(path)
}

/// Writes a dataset of simulated episodes at `root`: for every id and action, the episode of
/// seed `seed + id` at 64×64.
pub fn simulated_dataset(
    root: &Path,
    ids: impl IntoIterator<Item = u32>,
    actions: &[dmbn::sim::Action],
    seed: u64,
) {
    let mut writer = dmbn::data::DatasetWriter::create(root).unwrap();
    for id in ids {
        for &action in actions {
            let episode = dmbn::sim::episode(action, seed + id as u64, 64).unwrap();
            writer.write(id, action.name(), &episode).unwrap();
        }
    }
    writer.finish().unwrap();
}

/// Writes `model` as a model file at `path` (what `train` writes).
pub fn save_model(
    path: &Path,
    model: &dmbn::model::Model,
    normalization: &dmbn::model::Normalization,
    half: bool,
) {
    let bytes = dmbn::model::save_bytes(model, normalization, half).unwrap();
    dmbn::data::write_atomic(path, &bytes).unwrap();
}
