//! dmbn: multimodal action prediction with Conditional Neural Processes.
pub mod augment;
pub mod data;
#[cfg(not(target_arch = "wasm32"))]
pub mod eval;
#[cfg(not(target_arch = "wasm32"))]
pub mod figure;
pub mod futures;
pub mod imitate;
pub mod model;
pub mod predict;
pub mod quality;
pub mod sim;
#[cfg(not(target_arch = "wasm32"))]
pub mod train;
#[cfg(target_arch = "wasm32")]
pub mod web;
