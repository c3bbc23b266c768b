//! From sequences to what the models consume: context/target sampling into [`Batch`]es.
mod batch;
mod sampler;

pub use batch::{planar, Batch};
pub use sampler::{Sampler, SamplerConfig};
