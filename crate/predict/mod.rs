//! Inference, one implementation for the `dmbn predict` command, the evaluation and the wasm
//! page: [`Observations`] (context frames, joints and times, in dataset units) are encoded once
//! by a [`Predictor`], which then decodes any number of target times in chunks into a
//! [`SequencePrediction`] (mean and σ per pixel and per joint, back in dataset units).
//! [`pixel_sigma`] and [`heat_map`] turn σ into the colour map shown by the CLI and the page,
//! both scaled by [`SequencePrediction::max_image_sigma`]. Natively, [`prediction_arrays`] saves
//! a prediction with its inputs for comparison with other implementations.
#[cfg(not(target_arch = "wasm32"))]
mod arrays;
mod encoding;
mod heat_map;
mod observations;
mod predictor;
mod scores;
mod sequence_prediction;

#[cfg(not(target_arch = "wasm32"))]
pub use arrays::prediction_arrays;
pub use encoding::{Encoding, Reads};
pub use heat_map::{heat_map, heat_map_rgb, pixel_sigma};
pub use observations::Observations;
pub use predictor::Predictor;
pub use scores::Scores;
pub use sequence_prediction::SequencePrediction;
