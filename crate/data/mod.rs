//! Sequences and datasets in the original DMBN folder layout.
mod sequence;

pub use sequence::{Sequence, ENDPOINT, JOINTS};
