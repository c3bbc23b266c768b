use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::action::parse_action;
use super::Episode;
use crate::imitate::{self, Task};
use crate::sim::{self, Outcome, Trajectory};

/// A performance of a demonstration's action (`Model.imitate`, `replay`): the trajectory the
/// arm was given, the recorded performance and its outcome.
#[wasm_bindgen]
pub struct Imitation {
    inner: imitate::Imitation,
}

impl From<imitate::Imitation> for Imitation {
    fn from(inner: imitate::Imitation) -> Self {
        Imitation { inner }
    }
}

impl Imitation {
    /// The imitation, for Rust callers.
    pub fn inner(&self) -> &imitate::Imitation {
        &self.inner
    }
}

/// What `Imitation.outcome` returns: [`Outcome`]'s fields and its one-line summary.
#[derive(Serialize)]
struct OutcomeValue {
    #[serde(flatten)]
    outcome: Outcome,
    summary: String,
}

#[wasm_bindgen]
impl Imitation {
    /// `{action, success, lift_cm, object_error_cm, path_error_cm, summary}`: did the grasp
    /// lift the object 10 cm, did the push land it within 3 cm of the demonstration's spot, and
    /// a line for people ("lifted 21 cm").
    #[wasm_bindgen(getter)]
    pub fn outcome(&self) -> Result<JsValue, JsError> {
        let value = OutcomeValue {
            outcome: self.inner.outcome,
            summary: self.inner.outcome.summary(),
        };
        value
            .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
            .map_err(|e| JsError::new(&e.to_string()))
    }

    /// The trajectory performed, `Float32Array(T × 7)`: 6 angles (rad), gripper.
    pub fn trajectory(&self) -> Vec<f32> {
        self.inner.trajectory.as_flattened().to_vec()
    }

    /// The recorded performance, as an `Episode` (frames, reached joints, object track).
    pub fn performance(&self) -> Episode {
        Episode::from(self.inner.performance.clone())
    }

    /// The demonstration's steps the model observed, `Uint32Array` (empty for a replay).
    pub fn observed(&self) -> Vec<u32> {
        self.inner.observed.iter().map(|&k| k as u32).collect()
    }

    /// The first step performed as predicted (the steps before it as recorded).
    #[wasm_bindgen(getter, js_name = predictedFrom)]
    pub fn predicted_from(&self) -> usize {
        self.inner.predicted_from
    }

    /// RMSE of the trajectory's arm joints against the demonstration's from `predictedFrom` on.
    #[wasm_bindgen(getter, js_name = jointRmse)]
    pub fn joint_rmse(&self) -> f64 {
        self.inner.joint_rmse()
    }
}

/// `replay(episode, action)`: the arm performs the demonstration's own recorded joints with
/// the object where it was (the ceiling of `Model.imitate`).
#[wasm_bindgen]
pub fn replay(
    episode: &Episode,
    #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
) -> Result<Imitation, JsError> {
    let action = parse_action(&action)?;
    Ok(imitate::replay(episode.sequence(), action)?.into())
}

/// `enact(episode, action, trajectory, observed)`: the arm performs `trajectory`, a
/// `Float32Array(T × 7)` with a row per step of the demonstration `episode` (joint means
/// predicted from its `observed` steps, a `Uint32Array`, by the page's workers), with the
/// object where the demonstration had it, judged against it. Throws on a bad trajectory (a row
/// count other than the episode's, NaN, an angle beyond ±2π) or an observed step past its end.
#[wasm_bindgen]
pub fn enact(
    episode: &Episode,
    #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
    trajectory: &[f32],
    observed: &[u32],
) -> Result<Imitation, JsError> {
    let action = parse_action(&action)?;
    let demo = episode.sequence();
    let rows = Trajectory::from_flat(trajectory)?.rows().to_vec();
    let observed: Vec<usize> = observed.iter().map(|&k| k as usize).collect();
    if let Some(k) = observed.iter().find(|&&k| k >= demo.len()) {
        return Err(JsError::new(&format!(
            "observed step {k} is past the demonstration's {} steps",
            demo.len()
        )));
    }
    Ok(imitate::enact(demo, action, rows, observed)?.into())
}

/// `perform(trajectory, x, y, imageSize)`: the arm performs any `Float32Array(T × 7)` of joint
/// rows (6 angles in rad, the gripper value) with the object at `(x, y)`, as the native
/// simulator does; returns the recorded `Episode`. Throws on a bad trajectory (a row count
/// not a multiple of 7, NaN, an angle beyond ±2π, no row or over 2000) or placement.
#[wasm_bindgen]
pub fn perform(
    trajectory: &[f32],
    x: f32,
    y: f32,
    #[wasm_bindgen(js_name = imageSize)] image_size: u32,
) -> Result<Episode, JsError> {
    let trajectory = Trajectory::from_flat(trajectory)?;
    Ok(sim::perform(&trajectory, [x, y], image_size)?.into())
}

/// A JS value as a task name.
pub(crate) fn parse_task(value: &JsValue) -> Result<Task, JsError> {
    match value.as_string() {
        Some(name) => name.parse().map_err(|e: String| JsError::new(&e)),
        None => Err(JsError::new(&format!(
            "task must be a string (\"frames\" or \"finish\"), got {value:?}"
        ))),
    }
}

/// A JS number as a count of observations: an integer from 2 to 10,000.
pub(crate) fn parse_observations(value: f64) -> Result<usize, JsError> {
    if value.is_finite() && value.fract() == 0.0 && (2.0..=10_000.0).contains(&value) {
        Ok(value as usize)
    } else {
        Err(JsError::new(&format!(
            "observations is {value}: expected an integer from 2 to 10000"
        )))
    }
}
