//! Writing one sequence in the DMBN layout, each file atomically.
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

use super::layout::{endpoint_path, joint_path, object_path, sequence_dir, valid_action_name};
use super::{write_atomic, DataError, Sequence};

/// Write `seq` as `<root>/<id>/<action>/<k>.png` plus `joint_<id>.txt` and, where the
/// sequence has them, `object_<id>.txt` and `endpoint_<id>.txt` (values space separated in Rust's shortest round-trip `{}` format,
/// so the text is deterministic and reads back to the same `f32`s). Each file is written to a
/// hidden temporary name and renamed, so a reader never sees a half-written file. Returns the
/// sequence folder.
pub fn write_sequence(
    root: &Path,
    id: u32,
    action: &str,
    seq: &Sequence,
) -> Result<PathBuf, DataError> {
    check_sequence(id, action, seq)?;
    let dir = sequence_dir(root, id, action);
    fs::create_dir_all(&dir).map_err(DataError::io(&dir))?;

    let size = seq.image_size;
    for k in 0..seq.len() {
        let path = dir.join(format!("{k}.png"));
        let mut png = Vec::new();
        PngEncoder::new(&mut png)
            .write_image(seq.frame(k), size, size, ExtendedColorType::Rgb8)
            .map_err(|source| DataError::Encode {
                path: path.clone(),
                source,
            })?;
        write_atomic(&path, &png)?;
    }
    write_atomic(&joint_path(&dir, id), table(seq.joints.rows()).as_bytes())?;
    if let Some(object) = &seq.object {
        write_atomic(&object_path(&dir, id), table(object.iter()).as_bytes())?;
    }
    if let Some(endpoint) = &seq.endpoint {
        write_atomic(&endpoint_path(&dir, id), table(endpoint.iter()).as_bytes())?;
    }
    Ok(dir)
}

/// Refuse sequences that would not read back: ragged columns, wrong frame bytes, non-finite
/// values (the reader rejects them), or an unusable action folder name.
fn check_sequence(id: u32, action: &str, seq: &Sequence) -> Result<(), DataError> {
    if !valid_action_name(action) {
        return Err(DataError::ActionName {
            name: action.to_string(),
        });
    }
    let bad = |reason: String| DataError::InvalidSequence {
        id,
        action: action.to_string(),
        reason,
    };
    let t = seq.len();
    if t == 0 {
        return Err(bad("it has no step".into()));
    }
    if seq.image_size == 0 {
        return Err(bad("its image size is 0".into()));
    }
    let object = seq.object.as_deref().unwrap_or_default();
    let endpoint = seq.endpoint.as_deref().unwrap_or_default();
    let rows = |v: Option<usize>| v.map_or("no".to_string(), |n| n.to_string());
    if seq.object.as_ref().is_some_and(|o| o.len() != t)
        || seq.endpoint.as_ref().is_some_and(|e| e.len() != t)
    {
        return Err(bad(format!(
            "{t} joint rows but {} object rows and {} endpoint rows",
            rows(seq.object.as_ref().map(Vec::len)),
            rows(seq.endpoint.as_ref().map(Vec::len))
        )));
    }
    let expected = (seq.image_size as u64).pow(2) * 3 * t as u64;
    if seq.frames.len() as u64 != expected {
        return Err(bad(format!(
            "{} frame bytes, expected {expected} ({t} frames of {size}x{size} RGB)",
            seq.frames.len(),
            size = seq.image_size
        )));
    }
    let values = seq
        .joints
        .values()
        .iter()
        .chain(object.iter().flatten())
        .chain(endpoint.iter().flatten());
    if let Some(v) = values.into_iter().find(|v| !v.is_finite()) {
        return Err(bad(format!("it holds the non-finite value {v}")));
    }
    Ok(())
}

/// Rows of numbers as text: space separated, one row per line.
fn table<'a, R: AsRef<[f32]> + 'a>(rows: impl Iterator<Item = R>) -> String {
    let mut out = String::new();
    for row in rows {
        let row = row.as_ref();
        for (c, v) in row.iter().enumerate() {
            if c > 0 {
                out.push(' ');
            }
            let _ = write!(out, "{v}");
        }
        out.push('\n');
    }
    out
}
