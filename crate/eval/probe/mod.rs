//! The time-regression probe (the paper's Table 1): how much of a context's time each
//! encoder's encoding still carries, read back by a small head fitted on training steps and
//! scored on test steps.
mod checks;
mod encodings;
mod head;
mod report;
mod run;

pub use checks::{
    diverged, split_warnings, time_variance, DIVERGENCE_FACTOR, MIN_TEST_IDS, MIN_TEST_STEPS,
    MIN_TRAIN_IDS,
};
pub use encodings::{encode_steps, StepEncodings};
pub use head::{fit_head, HeadConfig};
pub use report::{Divergence, ProbeReport, ProbeResult, ProbeRow};
pub use run::{probe, ProbeConfig};
