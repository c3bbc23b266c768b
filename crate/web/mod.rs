//! JavaScript bindings (wasm32 only): thin wrappers that convert JS values to the Rust types of
//! [`crate::sim`] and [`crate::predict`] and back. No simulation logic lives here; bad arguments become JS exceptions.
mod action;
mod episode;
mod eval_episode;
mod model;
mod region;
mod seed;
mod simulator;
mod streaming;

pub use episode::{run_episode, Episode};
pub use eval_episode::EvalEpisode;
pub use model::{ModelHandle, Prediction};
pub use region::{placement_region, Region};
pub use simulator::Simulator;
pub use streaming::{Encoding, StreamingModel};
