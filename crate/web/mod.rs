//! JavaScript bindings (wasm32 only): thin wrappers that convert JS values to the Rust types of
//! [`crate::sim`] and [`crate::predict`] and back. No simulation logic lives here; bad arguments become JS exceptions.
mod argument;
mod contexts;
mod encoding;
mod episode;
mod eval_episode;
mod folder;
mod forecast_error;
mod heat_map;
mod imitation;
mod model;
mod region;
mod simulator;

pub use contexts::Contexts;
pub use encoding::Encoding;
pub use episode::{run_episode, Episode};
pub use eval_episode::EvalEpisode;
pub use folder::Folder;
pub use forecast_error::forecast_error;
pub use heat_map::heat_map;
pub use imitation::{enact, perform, perform_on_arm, replay, Imitation};
pub use model::{ModelHandle, Prediction};
pub use region::{placement_region, Region};
pub use simulator::Simulator;
