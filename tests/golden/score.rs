//! The golden quality benchmark shared by the native and the wasm tests: the shipped
//! default model on a simulated grasp in both scenarios. Native writes `score.json` (with
//! `DMBN_BLESS=1`) and checks itself against it; wasm (`Model.score`) must agree within 1e-4.
#![allow(dead_code)]

use dmbn::quality::{CoverageSummary, Quality, Scenario};

/// The model scored: the page's default.
pub const MODEL: &[u8] = include_bytes!("../../assets/models/attn-sim.dmbn");
/// Expected values, see [`sample`].
pub const JSON: &str = include_str!("score.json");
/// The episode: `episode(Action::Grasp, SEED, 64)`.
pub const SEED: u64 = 11;
/// Observations in `interp`.
pub const OBSERVATIONS: usize = 5;
/// Blending coefficient.
pub const BLEND: f32 = 0.5;
/// The scenarios, in the order of the sample.
pub const SCENARIOS: [Scenario; 2] = [Scenario::Interp, Scenario::Extrap];

/// Every measure of the model and of the baseline, NaN for an absent one.
pub fn sample(model: &Quality, baseline: &Quality) -> Vec<f64> {
    // The model's calibration last, by continuous measures (a coverage fraction of a few
    // hundred joint values could flip a count between builds that agree within 1e-4).
    let calibration = model.calibration.map_or([f64::NAN; 4], |c| {
        let of = |s: Option<CoverageSummary>, two: bool| {
            s.map_or(
                f64::NAN,
                |s| if two { s.two_sigma } else { s.sigma_to_rmse },
            )
        };
        [
            of(c.joints, false),
            of(c.pixels, false),
            of(c.pixels, true),
            of(c.moving_pixels, false),
        ]
    });
    [model, baseline]
        .iter()
        .flat_map(|q| {
            [
                q.joint_rmse,
                q.gripper_mae,
                q.image_mse,
                q.observed_joint_rmse,
                q.observed_image_mse,
                q.image_nll.unwrap_or(f64::NAN),
                q.joint_nll.unwrap_or(f64::NAN),
                q.object_iou.unwrap_or(f64::NAN),
                q.observed_object_iou.unwrap_or(f64::NAN),
            ]
        })
        .chain(calibration)
        .collect()
}

/// The expected samples, one per scenario (NaN stored as null).
pub fn expected() -> Vec<Vec<f64>> {
    let values: Vec<Vec<Option<f64>>> =
        serde_json::from_str(JSON).expect("tests/golden/score.json is a JSON array of arrays");
    values
        .into_iter()
        .map(|row| row.into_iter().map(|v| v.unwrap_or(f64::NAN)).collect())
        .collect()
}

/// The largest difference relative to max(1, |expected|), and where; NaN must match NaN.
pub fn max_diff(got: &[f64], want: &[f64]) -> (f64, usize) {
    assert_eq!(got.len(), want.len(), "sample lengths differ");
    got.iter()
        .zip(want)
        .enumerate()
        .map(|(i, (a, b))| {
            let d = if a.is_nan() && b.is_nan() {
                0.0
            } else {
                (a - b).abs() / b.abs().max(1.0)
            };
            (if d.is_nan() { f64::INFINITY } else { d }, i)
        })
        .fold((0.0, 0), |m, d| if d.0 > m.0 { d } else { m })
}
