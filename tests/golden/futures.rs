//! The golden sampled futures shared by the native and the wasm tests: the page's default model
//! finishing a simulated push from its first 30%, 3 futures at every step. Native writes
//! `futures.json` (with `DMBN_BLESS=1`) and reproduces it; wasm (`Model.sample`) must agree
//! within 1e-4 (the draws are the same bits; the means differ by the kernels' rounding).
#![allow(dead_code)]

/// The model: the page's default.
pub const MODEL: &[u8] = include_bytes!("../../assets/models/attn-sim.dmbn");
/// Expected values: `S × T × D` joint means, future by future.
pub const JSON: &str = include_str!("futures.json");
/// The demonstration: `episode(Action::Move, SEED, 64)`.
pub const SEED: u64 = 5;
/// Futures drawn, and their seed.
pub const SAMPLES: usize = 3;
pub const SAMPLE_SEED: u64 = 11;
/// Blending coefficient (finish's).
pub const BLEND: f32 = 0.5;

/// The expected values.
pub fn expected() -> Vec<f32> {
    serde_json::from_str(JSON).expect("tests/golden/futures.json is a JSON array of numbers")
}
