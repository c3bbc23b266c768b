//! dmbn: multimodal action prediction with Conditional Neural Processes.
pub mod data;
pub mod sim;
#[cfg(target_arch = "wasm32")]
pub mod web;
