//! What several commands take: parsers for their shared arguments, and the model and
//! sequence that `--model`, `--data` and `--sequence` name.
use std::path::Path;

use dmbn::data::{Dataset, Sequence};
use dmbn::predict::Predictor;

use crate::error::CliError;

/// An id range `A-B` (inclusive) or a single id (`--ids`, `--mean-ids`, `--test-ids`).
pub fn parse_ids(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{s:?} is not an id range A-B: expected e.g. 32-39 (or one id, 38)");
    let id = |v: &str| v.trim().parse::<u32>().map_err(|_| bad());
    let (a, b) = match s.split_once('-') {
        Some((a, b)) => (id(a)?, id(b)?),
        None => {
            let a = id(s)?;
            (a, a)
        }
    };
    if a > b {
        return Err(format!("{s:?}: A ({a}) must not exceed B ({b})"));
    }
    Ok((a, b))
}

/// A sequence as `ID/ACTION` (`--sequence`).
pub fn parse_sequence(s: &str) -> Result<(u32, String), String> {
    let bad = || format!("{s:?} is not ID/ACTION: expected e.g. 3/grasp");
    let (id, action) = s.split_once('/').ok_or_else(bad)?;
    let id = id.parse().map_err(|_| bad())?;
    if action.is_empty() {
        return Err(bad());
    }
    Ok((id, action.to_string()))
}

/// The blending coefficient c in [0, 1] (`--blend`).
pub fn parse_blend(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(c) if (0.0..=1.0).contains(&c) => Ok(c),
        _ => Err(format!(
            "{s:?} is not a blending coefficient: expected a number in [0, 1]"
        )),
    }
}

/// The model file at `model` and sequence `id`/`action` of the dataset at `data`, read at the
/// model's frame size (shared by `predict` and `eval`).
pub fn load(
    model: &Path,
    data: &Path,
    (id, action): &(u32, String),
) -> Result<(Predictor, Sequence), CliError> {
    let predictor = Predictor::load(model)?;
    let dataset = Dataset::open(data)?;
    let size = predictor.model().image_size() as u32;
    let seq = dataset.read(dataset.find(*id, action)?, Some(size))?;
    Ok((predictor, seq))
}
