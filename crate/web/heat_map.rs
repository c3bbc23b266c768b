use wasm_bindgen::prelude::*;

use crate::predict;

/// Pixel σ (a `Float32Array(S × S)`, as `Prediction.pixelSigma` gives it) as an RGB heat map,
/// `Uint8Array(S × S × 3)`, with `scale` (the largest σ, `Prediction.maxImageSigma`) shown as
/// full yellow: the ramp and the scaling of `sigmaMap` and of the σ images `dmbn predict`
/// writes.
#[wasm_bindgen(js_name = heatMap)]
pub fn heat_map(sigma: &[f32], scale: f32) -> Vec<u8> {
    predict::heat_map(sigma, scale)
}
