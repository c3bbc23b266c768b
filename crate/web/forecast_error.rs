use wasm_bindgen::prelude::*;

use crate::quality;

/// The quality benchmark's measures of a forecast the page drew (RGB bytes and joints for a
/// run of steps) against the true frames and joints of the same steps: the live mode's error
/// plot. Returns the fields `dmbn score --json` writes (`joint_rmse`, `image_mse`,
/// `object_iou`, …); throws, naming the argument, when the layouts disagree.
#[wasm_bindgen(js_name = forecastError)]
pub fn forecast_error(
    #[wasm_bindgen(js_name = trueFrames)] true_frames: &[u8],
    #[wasm_bindgen(js_name = trueJoints)] true_joints: &[f32],
    frames: &[u8],
    joints: &[f32],
) -> Result<JsValue, JsError> {
    let quality = quality::score_steps(true_frames, true_joints, frames, joints)
        .map_err(|e| JsError::new(&format!("forecastError: {e}")))?;
    serde::Serialize::serialize(&quality, &serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(|e| JsError::new(&e.to_string()))
}
