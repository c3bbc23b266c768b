//! The golden prediction shared by the native and the wasm tests: the shipped DMBN weights on
//! a simulated grasp, observed at three steps. Native writes `prediction.json` (with
//! `DMBN_BLESS=1`) and checks itself against it; wasm must agree within 1e-4.
#![allow(dead_code)]

use dmbn::predict::SequencePrediction;

/// The shipped simulator-trained DMBN.
pub const MODEL: &[u8] = include_bytes!("../../assets/models/dmbn-sim.dmbn");
/// Expected values, see [`sample`].
pub const JSON: &str = include_str!("prediction.json");
/// The episode: `episode(Action::Grasp, SEED, 64)`.
pub const SEED: u64 = 7;
/// Observed steps.
pub const OBSERVE: [usize; 3] = [0, 20, 40];
/// Blending coefficient.
pub const BLEND: f32 = 0.5;
/// Every this many values of the frames go into the sample.
pub const STRIDE: usize = 61;

/// What is compared: all joint means and σ, and every 61st value of the mean and σ frames.
pub fn sample(p: &SequencePrediction) -> Vec<f32> {
    p.joint_mean
        .iter()
        .chain(&p.joint_sigma)
        .chain(p.image_mean.iter().step_by(STRIDE))
        .chain(p.image_sigma.iter().step_by(STRIDE))
        .copied()
        .collect()
}

/// The expected sample.
pub fn expected() -> Vec<f32> {
    serde_json::from_str(JSON).expect("tests/golden/prediction.json is a JSON array of numbers")
}

/// The largest absolute difference, and where (panics on different lengths).
pub fn max_diff(a: &[f32], b: &[f32]) -> (f32, usize) {
    assert_eq!(a.len(), b.len(), "sample lengths differ");
    a.iter()
        .zip(b)
        .enumerate()
        .map(|(i, (x, y))| ((x - y).abs(), i))
        .fold((0.0, 0), |m, d| if d.0 > m.0 { d } else { m })
}

/// The page's σ heat-map scale, the largest of its decoded chunks' `max_image_sigma`
/// (`chunk_maxima`; www/prediction.js), checked to be within `tol` (relative) of `whole`, the
/// scale of the whole prediction at once (`dmbn predict`'s).
pub fn page_scale(chunk_maxima: impl IntoIterator<Item = f32>, whole: f32, tol: f32) -> f32 {
    let scale = chunk_maxima.into_iter().fold(0.0, f32::max);
    assert!(
        (scale - whole).abs() <= tol * whole,
        "the page's scale {scale}, the whole prediction's {whole}"
    );
    scale
}
