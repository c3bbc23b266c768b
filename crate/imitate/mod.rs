//! The imitation benchmark (Seker et al. 2022: a DMBN "connects observations with motor plans for
//! enaction"): shown a demonstration's frames, a model imagines its own joints, and the
//! simulated arm performs them with the object where the demonstration had it. The outcome
//! (did the grasp lift the object, did the push land it) is judged against the ceiling, the
//! demonstration's own recorded joints replayed, and the floor, the action's mean motion
//! replayed. Sampled futures ([`crate::futures`]) are performed one by one
//! ([`imitate_futures`]): how many are valid actions, and whether one of them succeeds. One
//! implementation natively (`dmbn imitate`) and in wasm (`Model.imitate`).
mod error;
mod futures;
mod imitation;
mod joint_noise;
mod report;
mod task;

pub use error::ImitateError;
pub use futures::{imitate_futures, FutureSums, FuturesReport, FuturesRow};
pub use imitation::{enact, imitate, mean_motion, replay, with_noise, Imitation};
pub use joint_noise::joint_noise;
pub use report::{ImitationReport, ImitationRow, OutcomeSums, PushMisses};
pub use task::Task;
pub use task::TaskSteps;
