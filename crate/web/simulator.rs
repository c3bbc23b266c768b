use wasm_bindgen::prelude::*;

use super::argument::{action, image_size, position, seed};
use super::Episode;
use crate::sim;

/// A running episode that JS advances one step at a time (for live animation), reading the
/// state and the rendered frame after each step.
#[wasm_bindgen]
pub struct Simulator {
    inner: sim::Simulator,
}

#[wasm_bindgen]
impl Simulator {
    /// `new Simulator(action, seed, imageSize)`: `action` is "grasp" or "move", `seed` places
    /// the object, `imageSize` is 64 or 128.
    #[wasm_bindgen(constructor)]
    pub fn new(
        #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
        #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
    ) -> Result<Simulator, JsError> {
        let (action, seed, size) = (
            action(&action_value)?,
            seed(&seed_value)?,
            image_size(&size)?,
        );
        let inner = sim::Simulator::new(action, seed, size)?;
        Ok(Simulator { inner })
    }

    /// `Simulator.withObject(action, x, y, seed, imageSize)`: the object at `(x, y)` metres,
    /// which must lie in `placementRegion()`.
    #[wasm_bindgen(js_name = withObject)]
    pub fn with_object(
        #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] x: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] y: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
        #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
    ) -> Result<Simulator, JsError> {
        let action = action(&action_value)?;
        let [x, y] = position(&x, &y)?;
        let (seed, size) = (seed(&seed_value)?, image_size(&size)?);
        let inner = sim::Simulator::with_object(action, x, y, seed, size)?;
        Ok(Simulator { inner })
    }

    /// Number of recorded steps the episode will have.
    #[wasm_bindgen(getter, js_name = len)]
    pub fn steps(&self) -> usize {
        self.inner.len()
    }

    /// Index of the current step (0 after construction).
    #[wasm_bindgen(getter, js_name = stepIndex)]
    pub fn step_index(&self) -> usize {
        self.inner.step_index()
    }

    /// Frame width and height in pixels.
    #[wasm_bindgen(getter, js_name = imageSize)]
    pub fn image_size(&self) -> u32 {
        self.inner.image_size()
    }

    /// Advance one step; false (and no change) once the episode is over.
    pub fn step(&mut self) -> bool {
        self.inner.step()
    }

    /// Joint values at the current step as a `Float32Array(7)`: 6 angles (rad), gripper.
    pub fn joints(&self) -> Vec<f32> {
        self.inner.joints().to_vec()
    }

    /// End effector at the current step as a `Float32Array(7)`: xyz, orientation, gripper.
    pub fn endpoint(&self) -> Vec<f32> {
        self.inner.endpoint().to_vec()
    }

    /// Object position at the current step as a `Float32Array(3)`.
    pub fn object(&self) -> Vec<f32> {
        self.inner.object().to_vec()
    }

    /// RGB frame of the current step as a `Uint8Array(imageSize² × 3)`, rows top to bottom
    /// (rendered anew on each call).
    pub fn frame(&mut self) -> Vec<u8> {
        self.inner.frame()
    }

    /// Record the rest of the episode (current step included) as an `Episode`; this
    /// simulator is consumed and must not be used afterwards.
    pub fn run(self) -> Episode {
        Episode::from(self.inner.run())
    }
}
