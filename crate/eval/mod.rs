//! The paper's evaluation (native): reconstruction of t/p/f sequences from K observations
//! ([`evaluate`], drawn by [`crate::figure::eval_figure`]) and the time-regression probe
//! ([`probe`]) that asks how much of a context's time its encoding still carries.
mod confidence;
mod evaluation;
mod probe;
mod standardizer;

pub use confidence::{mean_ci95, MeanCi};
pub use evaluation::{evaluate, evenly_spaced, Evaluation};
pub use probe::{
    diverged, encode_steps, fit_head, probe, split_warnings, time_variance, Divergence, HeadConfig,
    ProbeConfig, ProbeReport, ProbeResult, ProbeRow, StepEncodings, DIVERGENCE_FACTOR,
    MIN_TEST_IDS, MIN_TEST_STEPS, MIN_TRAIN_IDS,
};
pub use standardizer::{ABS_STD_FLOOR, REL_STD_FLOOR, STANDARD_CLIP};
