//! The golden imitation shared by the native and the wasm tests: the page's default model
//! imitates a simulated grasp in both tasks. Native writes `imitation.json` (with
//! `DMBN_BLESS=1`) and reproduces it exactly; wasm (`Model.imitate`) must predict the same
//! trajectory within 1e-4 and reach the same outcome, and the simulator must perform the
//! golden trajectory bit for bit (`perform`).
#![allow(dead_code)]

use serde::{Deserialize, Serialize};

use dmbn::sim::{Action, Outcome};

/// The model: the page's default.
pub const MODEL: &[u8] = include_bytes!("../../assets/models/attn-sim.dmbn");
/// Expected values.
pub const JSON: &str = include_str!("imitation.json");
/// The demonstration: `episode(ACTION, SEED, 64)`.
pub const ACTION: Action = Action::Grasp;
pub const SEED: u64 = 13;

/// One task's imitation (`frames` with 5 observations and blend 1, then `finish` with 0.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// The performed trajectory, `T × 7`.
    pub trajectory: Vec<f32>,
    pub success: bool,
    pub lift_cm: f32,
    pub object_error_cm: f32,
    pub path_error_cm: f32,
    /// `Sequence::digest` of the performance.
    pub performance_digest: String,
}

impl Sample {
    pub fn of(trajectory: &[impl AsRef<[f32]>], outcome: &Outcome, digest: &str) -> Sample {
        Sample {
            trajectory: trajectory
                .iter()
                .flat_map(|r| r.as_ref())
                .copied()
                .collect(),
            success: outcome.success,
            lift_cm: outcome.lift_cm,
            object_error_cm: outcome.object_error_cm,
            path_error_cm: outcome.path_error_cm,
            performance_digest: digest.to_string(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Golden {
    /// One sample per task.
    pub tasks: Vec<Sample>,
    /// `Sequence::digest` of the demonstration's recorded joints performed.
    pub replay_digest: String,
}

pub fn expected() -> Golden {
    serde_json::from_str(JSON).expect("tests/golden/imitation.json holds a Golden")
}

/// `got` against `want`: the trajectories within `tolerance` (relative to max(1, |want|));
/// with 0, everything identical; otherwise the same success and the outcome's distances
/// within 2 cm (a trajectory a hair different moves a gripped object a little differently:
/// 0.7 cm of lift, measured; the same trajectory is performed bit for bit, which the wasm test
/// checks apart).
pub fn assert_agrees(got: &Sample, want: &Sample, tolerance: f32) {
    assert_eq!(
        got.trajectory.len(),
        want.trajectory.len(),
        "trajectory lengths"
    );
    let (diff, at) = got
        .trajectory
        .iter()
        .zip(&want.trajectory)
        .map(|(a, b)| (a - b).abs() / b.abs().max(1.0))
        .enumerate()
        .fold(
            (0.0f32, 0),
            |m, (i, d)| if d > m.0 || d.is_nan() { (d, i) } else { m },
        );
    assert!(diff <= tolerance, "trajectory differs by {diff} at {at}");
    if tolerance == 0.0 {
        assert_eq!(got, want);
        return;
    }
    assert_eq!(got.success, want.success, "{got:?} against {want:?}");
    for (a, b) in [
        (got.lift_cm, want.lift_cm),
        (got.object_error_cm, want.object_error_cm),
        (got.path_error_cm, want.path_error_cm),
    ] {
        assert!((a - b).abs() < 2.0, "{a} against {b} cm");
    }
}
