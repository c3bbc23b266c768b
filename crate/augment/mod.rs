//! From sequences to what the models consume: context/target sampling into [`Batch`]es, the
//! paper's time-warp augmentation ([`TimeWarpConfig`]) and its evaluation sequences
//! ([`EvalSequence`]: t, p, f). Compiled for wasm too (the page shows p and f sequences).
mod batch;
mod error;
mod eval_sequence;
mod joint_targets;
mod sampler;
mod selection;
mod time_warp;

pub use batch::{planar, Batch};
pub use error::AugmentError;
pub use eval_sequence::{EvalMode, EvalSequence};
pub use joint_targets::JointTargets;
pub use sampler::{Sampler, SamplerConfig};
pub use selection::{Pick, Selection, Step};
pub use time_warp::{gather, TimeWarpConfig};
