use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::argument::{action, floats, image_size, indices, position};
use super::Episode;
use crate::imitate;
use crate::sim::{self, Arm, Outcome, Trajectory};

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
    /// `{action, success, lift_cm, object_error_cm, push_error_cm, path_error_cm, summary}`:
    /// did the grasp lift the object 10 cm, did the push land it within 3 cm of the
    /// demonstration's spot (`push_error_cm`: `{along, across}` of its push, `null` for a
    /// grasp), and a line for people ("lifted 21 cm").
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

    /// The trajectory performed, `Float32Array(T × D)`: the arm's angles (rad), gripper.
    pub fn trajectory(&self) -> Vec<f32> {
        self.inner.trajectory.concat()
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
    #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
) -> Result<Imitation, JsError> {
    let action = action(&action_value)?;
    Ok(imitate::replay(episode.sequence(), action)?.into())
}

/// `enact(episode, action, trajectory, observed)`: the arm performs `trajectory`, a
/// `Float32Array(T × D)` (D the episode's joint values a step: its arm's) with a row per
/// step of the demonstration `episode` (joint means
/// predicted from its `observed` steps, a `Uint32Array`, by the page's workers), with the
/// object where the demonstration had it, judged against it. Throws on a bad trajectory (a row
/// count other than the episode's, NaN, an angle beyond ±2π) or an observed step past its end.
#[wasm_bindgen]
pub fn enact(
    episode: &Episode,
    #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
    #[wasm_bindgen(unchecked_param_type = "Float32Array")] trajectory: JsValue,
    #[wasm_bindgen(unchecked_param_type = "Uint32Array")] observed: JsValue,
) -> Result<Imitation, JsError> {
    let action = action(&action_value)?;
    let demo = episode.sequence();
    let trajectory = floats(&trajectory, "trajectory")?;
    let arm = Arm::of_width(demo.joints.width())?;
    let performed = Trajectory::from_flat_on(arm, &trajectory)?;
    let rows: Vec<&[f32]> = performed.joints().rows().collect();
    let observed = indices(&observed, "observed")?;
    if let Some(k) = observed.iter().find(|&&k| k >= demo.len()) {
        return Err(JsError::new(&format!(
            "observed step {k} is past the demonstration's {} steps",
            demo.len()
        )));
    }
    Ok(imitate::enact(demo, action, rows, observed)?.into())
}

/// `perform(trajectory, x, y, imageSize)` for Rust callers: the UR5 performs.
pub fn perform(
    trajectory: JsValue,
    x: JsValue,
    y: JsValue,
    size: JsValue,
) -> Result<Episode, JsError> {
    perform_on_arm(trajectory, x, y, size, JsValue::UNDEFINED)
}

/// `perform(trajectory, x, y, imageSize, arm?)`: `arm` ("ur5", left out, or "panda") performs
/// any `Float32Array(T × D)` of joint rows (D = 7 for the UR5: 6 angles in rad and the
/// gripper; 8 for the Panda) with the object at `(x, y)`, as the native simulator does;
/// returns the recorded `Episode`. Throws on a bad trajectory (a value count not a multiple
/// of D, NaN, an angle beyond ±2π, no row or over 2000), arm or placement.
#[wasm_bindgen(js_name = perform)]
pub fn perform_on_arm(
    #[wasm_bindgen(unchecked_param_type = "Float32Array")] trajectory: JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] x: JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] y: JsValue,
    #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
    #[wasm_bindgen(unchecked_param_type = "string | undefined")] arm: JsValue,
) -> Result<Episode, JsError> {
    let arm = super::simulator::arm(&arm)?;
    let trajectory = floats(&trajectory, "trajectory")?;
    let trajectory = Trajectory::from_flat_on(arm, &trajectory)?;
    let position = position(&x, &y)?;
    Ok(sim::perform(&trajectory, position, image_size(&size)?)?.into())
}
