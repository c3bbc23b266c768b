use serde::Serialize;
use wasm_bindgen::prelude::*;

use crate::sim::Simulator;

/// Where objects may be placed, as `{x: [x0, x1], y: [y0, y1]}` in metres (arm-base frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Region {
    pub x: [f64; 2],
    pub y: [f64; 2],
}

/// The shortest decimal that reads back as the same `f32`, so JS sees `-0.15`, not
/// `-0.15000000596046448`, and passing it back to `withObject` gives the same bound.
fn shortest(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

impl Region {
    /// [`Simulator::REGION`] in JS-friendly numbers.
    pub fn new() -> Self {
        let ([x0, x1], [y0, y1]) = Simulator::REGION;
        Region {
            x: [shortest(x0), shortest(x1)],
            y: [shortest(y0), shortest(y1)],
        }
    }
}

impl Default for Region {
    fn default() -> Self {
        Self::new()
    }
}

/// The object placement region `{x: [x0, x1], y: [y0, y1]}` accepted by `Simulator.withObject`.
#[wasm_bindgen(
    js_name = placementRegion,
    unchecked_return_type = "{ x: [number, number], y: [number, number] }"
)]
pub fn placement_region() -> Result<JsValue, JsError> {
    Ok(serde_wasm_bindgen::to_value(&Region::new())?)
}
