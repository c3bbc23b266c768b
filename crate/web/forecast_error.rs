use wasm_bindgen::prelude::*;

use super::argument::{bytes, floats, index};
use crate::quality;

/// The quality benchmark's measures of a forecast the page drew (RGB bytes and joints for a
/// run of steps) against the true frames and joints of the same steps: the live mode's error
/// plot. Returns the fields `dmbn score --json` writes (`joint_rmse`, `image_mse`,
/// `object_iou`, …); throws, naming the argument, when the layouts disagree. `jointCount`:
/// joint values a step (the model's; 7, the simulator arm's, when left out).
#[wasm_bindgen(js_name = forecastError)]
pub fn forecast_error(
    #[wasm_bindgen(js_name = trueFrames, unchecked_param_type = "Uint8Array")] true_frames: JsValue,
    #[wasm_bindgen(js_name = trueJoints, unchecked_param_type = "Float32Array")]
    true_joints: JsValue,
    #[wasm_bindgen(unchecked_param_type = "Uint8Array")] frames: JsValue,
    #[wasm_bindgen(unchecked_param_type = "Float32Array")] joints: JsValue,
    #[wasm_bindgen(js_name = jointCount, unchecked_param_type = "number | undefined")]
    joint_count: JsValue,
) -> Result<JsValue, JsError> {
    let d = if joint_count.is_undefined() {
        crate::data::JOINTS
    } else {
        index(&joint_count, "jointCount")?
    };
    let (true_frames, true_joints) = (
        bytes(&true_frames, "trueFrames")?,
        floats(&true_joints, "trueJoints")?,
    );
    let (frames, joints) = (bytes(&frames, "frames")?, floats(&joints, "joints")?);
    let quality = quality::score_steps(&true_frames, &true_joints, &frames, &joints, d)
        .map_err(|e| JsError::new(&format!("forecastError: {e}")))?;
    serde::Serialize::serialize(&quality, &serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(|e| JsError::new(&e.to_string()))
}
