use wasm_bindgen::prelude::*;

use super::argument::{action, choice, image_size, position, seed};
use super::Episode;
use crate::sim::{self, Arm};

/// A running episode that JS advances one step at a time (for live animation), reading the
/// state and the rendered frame after each step.
#[wasm_bindgen]
pub struct Simulator {
    inner: sim::Simulator,
}

/// `arm`: `"ur5"` or `"panda"`; `undefined` (or `null`: left out) is the UR5.
pub(super) fn arm(value: &JsValue) -> Result<Arm, JsError> {
    if value.is_undefined() || value.is_null() {
        return Ok(Arm::Ur5);
    }
    choice(value, "arm", &Arm::names_text())
}

/// For Rust callers: the JS signatures without the optional arm (the UR5's episodes).
impl Simulator {
    /// `new Simulator(action, seed, imageSize)`.
    pub fn new(action: JsValue, seed: JsValue, size: JsValue) -> Result<Simulator, JsError> {
        Simulator::new_with_arm(action, seed, size, JsValue::UNDEFINED)
    }

    /// `Simulator.withObject(action, x, y, seed, imageSize)`.
    pub fn with_object(
        action: JsValue,
        x: JsValue,
        y: JsValue,
        seed: JsValue,
        size: JsValue,
    ) -> Result<Simulator, JsError> {
        Simulator::with_object_on_arm(action, x, y, seed, size, JsValue::UNDEFINED)
    }
}

#[wasm_bindgen]
impl Simulator {
    /// `new Simulator(action, seed, imageSize, arm?)`: `action` is "grasp" or "move", `seed`
    /// places the object, `imageSize` is 64 or 128, `arm` "ur5" (left out) or "panda".
    #[wasm_bindgen(constructor)]
    pub fn new_with_arm(
        #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
        #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
        #[wasm_bindgen(js_name = arm, unchecked_param_type = "string | undefined")]
        arm_value: JsValue,
    ) -> Result<Simulator, JsError> {
        let (action, seed, size, arm) = (
            action(&action_value)?,
            seed(&seed_value)?,
            image_size(&size)?,
            arm(&arm_value)?,
        );
        let inner = sim::Simulator::new_with_arm(arm, action, seed, size)?;
        Ok(Simulator { inner })
    }

    /// `Simulator.withObject(action, x, y, seed, imageSize, arm?)`: the object at `(x, y)`
    /// metres, which must lie in `placementRegion()`.
    #[wasm_bindgen(js_name = withObject)]
    pub fn with_object_on_arm(
        #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] x: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] y: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
        #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
        #[wasm_bindgen(js_name = arm, unchecked_param_type = "string | undefined")]
        arm_value: JsValue,
    ) -> Result<Simulator, JsError> {
        let action = action(&action_value)?;
        let [x, y] = position(&x, &y)?;
        let (seed, size) = (seed(&seed_value)?, image_size(&size)?);
        let arm = arm(&arm_value)?;
        let inner = sim::Simulator::with_object_on(arm, action, x, y, seed, size)?;
        Ok(Simulator { inner })
    }

    /// The arm performing: "ur5" or "panda".
    #[wasm_bindgen(getter)]
    pub fn arm(&self) -> String {
        self.inner.arm().name().to_string()
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

    /// Joint values at the current step as a `Float32Array(D)`: the arm's angles (rad; 6
    /// for the UR5, 7 for the Panda), gripper.
    pub fn joints(&self) -> Vec<f32> {
        self.inner.joints()
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
