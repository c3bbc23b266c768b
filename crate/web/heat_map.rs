use wasm_bindgen::prelude::*;

use super::argument::{floats, number};
use crate::predict;

/// Pixel σ (a `Float32Array(S × S)`, as `Prediction.pixelSigma` gives it) as an RGB heat map,
/// `Uint8Array(S × S × 3)`, with `scale` (the largest σ, `Prediction.maxImageSigma`) shown as
/// full yellow: the ramp and the scaling of `sigmaMap` and of the σ images `dmbn predict`
/// writes.
#[wasm_bindgen(js_name = heatMap)]
pub fn heat_map(
    #[wasm_bindgen(unchecked_param_type = "Float32Array")] sigma: JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] scale: JsValue,
) -> Result<Vec<u8>, JsError> {
    let sigma = floats(&sigma, "sigma")?;
    let scale = number(&scale, "scale", 0.0, f64::MAX)? as f32;
    Ok(predict::heat_map(&sigma, scale))
}
