//! The paper's evaluation (native): reconstruction of t/p/f sequences from K observations
//! ([`evaluate`], drawn by [`crate::figure::eval_figure`]) and the time-regression probe
//! ([`probe`]) that asks how much of a context's time its encoding still carries.
mod confidence;
mod evaluation;
mod probe;

pub use confidence::{mean_ci95, MeanCi};
pub use evaluation::{evaluate, evenly_spaced, Evaluation};
pub use probe::{
    encode_steps, fit_head, probe, Encodings, HeadConfig, ProbeConfig, ProbeReport, ProbeResult,
    ProbeRow,
};
