//! Inference, one implementation for the `dmbn predict` command, the evaluation and the wasm
//! page: [`Observations`] (context frames, joints and times, in dataset units) are encoded once
//! by a [`Predictor`], which then decodes any number of target times in chunks into a
//! [`SequencePrediction`] (mean and σ per pixel and per joint, back in dataset units).
//! [`heat_map`] turns σ into the colour map shown by the CLI and the page.
mod heat_map;
mod observations;
mod predictor;
mod scores;
mod sequence_prediction;

pub use heat_map::{heat_map, heat_map_rgb};
pub use observations::Observations;
pub use predictor::Predictor;
pub use scores::Scores;
pub use sequence_prediction::SequencePrediction;
