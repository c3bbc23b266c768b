//! Many futures: coherent samples of what may come after the observations, where one mean is
//! the wrong answer (how far a push goes is not in its first 30%).
//!
//! A CNP predicts a Gaussian per target step, independently: drawing each step from its own
//! marginal gives jitter, not a trajectory. Deployed autoregressively (Bruinsma et al.,
//! "Autoregressive Conditional Neural Processes", ICLR 2023; wesselb/neuralprocesses'
//! `ar_predict`), the same network gives coherent samples: the future is drawn at a sparse grid
//! of target steps one after another, each draw (joints, and the predicted frame there) added
//! to the contexts before the next, then the mean at every step is decoded conditioned on the
//! contexts plus the drawn points: one smooth trajectory per sample ([`draw_futures`]). A
//! drawn step's joints vary together as the model file's [`crate::model::JointCorrelation`]
//! says, and by default the S futures kept are the [`representatives`] of more draws, so that
//! they spread over what may happen instead of clumping.
//! [`EnergyScore`] judges a set of sampled trajectories against the truth (a strictly proper
//! score for samples), beside the single mean's.
mod autoregressive;
mod energy_score;
mod representatives;
mod sampling;

pub use autoregressive::{
    draw_futures, draw_futures_from, draw_unobserved, drawn_step_errors, frames_at,
    sample_trajectories, sample_unobserved, score_futures, trajectories, DrawnStepError, Future,
};
pub use energy_score::{EnergyScore, FutureScoreRow, FutureScoreSums, FutureScores};
pub use representatives::representatives;
pub use sampling::{JointDraws, Method, Order, Sampling};
