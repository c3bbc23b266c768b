//! The quality benchmark: a model's predictions on sequences it never saw, against the trivial
//! baselines a CNP must beat (joints linearly interpolated between the observations and held
//! outside them, the nearest observation's frame; for extrapolation that is holding the last
//! observation), and optionally each action's mean motion. One implementation natively
//! (`dmbn score`) and in wasm (`Model.score`).
mod accumulator;
mod calibration;
mod forecast;
mod mean_motion;
mod object_mask;
mod report;
mod scenario;

pub use accumulator::{Accumulator, Quality};
pub use calibration::{
    joint_z_scores, two_sigma_scale, Calibration, Coverage, CoverageSummary, JointZScores, LEVELS,
    MOVING, TWO_SIGMA,
};
pub use forecast::score_steps;
pub use mean_motion::MeanMotion;
pub use object_mask::{is_object, OBJECT_COLOUR};
pub use report::{score_sequence, QualityReport, QualityRow, SequenceScores};
pub use scenario::{Scenario, ScenarioSteps};
