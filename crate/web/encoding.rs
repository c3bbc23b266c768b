use wasm_bindgen::prelude::*;

use crate::predict;

/// Observations encoded by `Model.encode` (or `Model.represent`): what the decoders are conditioned on (the blended
/// representation r, or the contexts the attentive model attends to), with the model that
/// made it (an id), so that it is only ever decoded by that model.
#[wasm_bindgen]
pub struct Encoding {
    pub(super) inner: predict::Encoding,
    pub(super) model: u32,
}
