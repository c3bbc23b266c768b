use wasm_bindgen::prelude::*;

use super::argument::{self, floats, index};
use super::Simulator;
use crate::data::{Normalization, Sequence, JOINTS};

/// A whole recorded episode, kept in wasm memory; JS copies out only the arrays it asks for.
#[wasm_bindgen]
pub struct Episode {
    inner: Sequence,
}

impl From<Sequence> for Episode {
    fn from(inner: Sequence) -> Self {
        Episode { inner }
    }
}

impl Episode {
    /// The recorded sequence, for Rust callers.
    pub fn sequence(&self) -> &Sequence {
        &self.inner
    }
}

#[wasm_bindgen]
impl Episode {
    /// Number of steps T.
    #[wasm_bindgen(getter, js_name = len)]
    pub fn steps(&self) -> usize {
        self.inner.len()
    }

    /// Frame width and height in pixels.
    #[wasm_bindgen(getter, js_name = imageSize)]
    pub fn image_size(&self) -> u32 {
        self.inner.image_size
    }

    /// Joint values as a `Float32Array(T × 7)`, step-major: 6 angles (rad), gripper.
    pub fn joints(&self) -> Vec<f32> {
        self.inner.joints.as_flattened().to_vec()
    }

    /// End effector as a `Float32Array(T × 7)`, step-major: xyz, orientation, gripper.
    pub fn endpoint(&self) -> Vec<f32> {
        self.inner.endpoint.as_flattened().to_vec()
    }

    /// Object position as a `Float32Array(T × 3)`, step-major.
    pub fn object(&self) -> Vec<f32> {
        self.inner.object.as_flattened().to_vec()
    }

    /// Phase of each step as a `Float32Array(T)`, `linspace(0, 1, T)`.
    pub fn times(&self) -> Vec<f32> {
        self.inner.times()
    }

    /// All frames as one `Uint8Array(T × imageSize² × 3)`: RGB, rows top to bottom.
    pub fn frames(&self) -> Vec<u8> {
        self.inner.frames.clone()
    }

    /// Frame `k` as a `Uint8Array(imageSize² × 3)`; throws when `k` is not a step index.
    pub fn frame(
        &self,
        #[wasm_bindgen(unchecked_param_type = "number")] k: JsValue,
    ) -> Result<Vec<u8>, JsError> {
        let k = index(&k, "k")?;
        if k < self.inner.len() {
            Ok(self.inner.frame(k).to_vec())
        } else {
            Err(JsError::new(&format!(
                "frame index {k} is out of range: the episode has {} frames",
                self.inner.len()
            )))
        }
    }

    /// How far the episode's joints lie from a model's joint normalisation (`Model.normalization`'s
    /// `mean` and `std`): the mean squared normalised joint value. The page offers the models
    /// whose normalisation a folder's sequence fits best. Throws unless both have 7 values.
    #[wasm_bindgen(js_name = jointDistance)]
    pub fn joint_distance(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] mean: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] std: JsValue,
    ) -> Result<f64, JsError> {
        let seven = |value: &JsValue, name| {
            let values = floats(value, name)?;
            <[f32; JOINTS]>::try_from(values.as_slice())
                .map_err(|_| argument::wrong(name, "a Float32Array of 7 values", value))
        };
        let (mean, std) = (seven(&mean, "mean")?, seven(&std, "std")?);
        Ok(Normalization { mean, std }.distance(&self.inner.joints))
    }

    /// SHA-256 (hex) fingerprint of the episode, equal to the native `Sequence::digest`.
    pub fn digest(&self) -> String {
        self.inner.digest()
    }
}

/// `runEpisode(action, seed, imageSize)`: simulate and render a whole episode in one call.
#[wasm_bindgen(js_name = runEpisode)]
pub fn run_episode(
    #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] seed: JsValue,
    #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
) -> Result<Episode, JsError> {
    Ok(Simulator::new(action, seed, size)?.run())
}
