//! dmbn: multimodal action prediction with Conditional Neural Processes.
pub mod data;
pub mod sim;
