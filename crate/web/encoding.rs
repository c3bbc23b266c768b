use js_sys::{Float32Array, Object, Reflect, Uint8Array};
use wasm_bindgen::prelude::*;

use crate::model::Representation;
use crate::predict::SequencePrediction;

/// Observations encoded by `Model.encode`: what the decoders are conditioned on (the blended
/// representation r, or the contexts the attentive model attends to), with the model that
/// made it (an id), so that it is only ever decoded by that model.
#[wasm_bindgen]
pub struct Encoding {
    pub(super) inner: Representation,
    pub(super) model: u32,
}

/// `p` as the plain object `Model.decode` returns: `{len, meanFrames, sigma, maxSigma,
/// jointMean, jointSigma}`, typed arrays ready to transfer.
pub(super) fn decoded_object(p: &SequencePrediction) -> Result<JsValue, JsError> {
    let means: Vec<u8> = (0..p.len()).flat_map(|k| p.mean_frame(k)).collect();
    let sigma: Vec<f32> = p
        .image_sigma
        .chunks_exact(3)
        .map(|px| (px[0] + px[1] + px[2]) / 3.0)
        .collect();
    let max_sigma = sigma.iter().copied().fold(0.0, f32::max);
    let out = Object::new();
    let f32s = |v: &[f32]| JsValue::from(Float32Array::from(v));
    let fields = [
        ("len", JsValue::from(p.len() as u32)),
        ("meanFrames", Uint8Array::from(means.as_slice()).into()),
        ("sigma", f32s(&sigma)),
        ("maxSigma", JsValue::from(max_sigma)),
        ("jointMean", f32s(&p.joint_mean)),
        ("jointSigma", f32s(&p.joint_sigma)),
    ];
    for (key, value) in fields {
        Reflect::set(&out, &JsValue::from_str(key), &value)
            .map_err(|_| JsError::new("could not build the prediction object"))?;
    }
    Ok(out.into())
}
