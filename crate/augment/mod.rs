//! From sequences to what the models consume: context/target sampling into [`Batch`]es.
mod batch;

pub use batch::Batch;
