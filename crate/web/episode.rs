use wasm_bindgen::prelude::*;

use super::argument::{self, floats, index};
use super::Simulator;
use crate::data::{Normalization, Sequence};

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

    /// Joint values a step (D): the simulator's UR5 has 7 (6 angles, gripper), its Panda 8.
    #[wasm_bindgen(getter, js_name = jointCount)]
    pub fn joint_count(&self) -> usize {
        self.inner.joints.width()
    }

    /// Joint values as a `Float32Array(T × D)`, step-major (the simulator's: 6 angles in
    /// radians, gripper).
    pub fn joints(&self) -> Vec<f32> {
        self.inner.joints.values().to_vec()
    }

    /// End effector as a `Float32Array(T × 7)`, step-major: xyz, orientation, gripper; empty
    /// where the data has no `endpoint_<id>.txt`.
    pub fn endpoint(&self) -> Vec<f32> {
        self.inner
            .endpoint
            .as_deref()
            .unwrap_or_default()
            .as_flattened()
            .to_vec()
    }

    /// Object position as a `Float32Array(T × 3)`, step-major; empty where the data has no
    /// `object_<id>.txt`.
    pub fn object(&self) -> Vec<f32> {
        self.inner
            .object
            .as_deref()
            .unwrap_or_default()
            .as_flattened()
            .to_vec()
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
    /// whose normalisation a folder's sequence fits best. Throws unless both have as many
    /// values as the episode has joint values a step.
    #[wasm_bindgen(js_name = jointDistance)]
    pub fn joint_distance(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] mean: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] std: JsValue,
    ) -> Result<f64, JsError> {
        let d = self.inner.joints.width();
        let values = |value: &JsValue, name| {
            let values = floats(value, name)?;
            if values.len() == d {
                Ok(values)
            } else {
                Err(argument::wrong(
                    name,
                    &format!("a Float32Array of {d} values (the episode's joint values a step)"),
                    value,
                ))
            }
        };
        let (mean, std) = (values(&mean, "mean")?, values(&std, "std")?);
        Ok(Normalization { mean, std }.distance(self.inner.joints.rows()))
    }

    /// SHA-256 (hex) fingerprint of the episode, equal to the native `Sequence::digest`.
    pub fn digest(&self) -> String {
        self.inner.digest()
    }
}

/// `runEpisode(action, seed, imageSize)` for Rust callers: the UR5's episode.
pub fn run_episode(action: JsValue, seed: JsValue, size: JsValue) -> Result<Episode, JsError> {
    run_arm_episode(action, seed, size, JsValue::UNDEFINED)
}

/// `runEpisode(action, seed, imageSize, arm?)`: simulate and render a whole episode in one
/// call; `arm` is "ur5" (left out) or "panda".
#[wasm_bindgen(js_name = runEpisode)]
pub fn run_arm_episode(
    #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
    #[wasm_bindgen(unchecked_param_type = "number")] seed: JsValue,
    #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
    #[wasm_bindgen(unchecked_param_type = "string | undefined")] arm: JsValue,
) -> Result<Episode, JsError> {
    Ok(Simulator::new_with_arm(action, seed, size, arm)?.run())
}
