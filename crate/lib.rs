//! dmbn: multimodal action prediction with Conditional Neural Processes.
pub mod augment;
pub mod data;
pub mod model;
pub mod sim;
#[cfg(target_arch = "wasm32")]
pub mod web;
