use wasm_bindgen::JsError;

/// Largest integer a JS number holds exactly; larger seeds would silently alias each other.
const MAX_SAFE: f64 = 9_007_199_254_740_992.0; // 2^53

/// A JS number as a seed: it must be a finite, non-negative integer no larger than 2^53, so that
/// the same number always means the same episode in JS and in Rust.
pub(crate) fn parse_seed(value: f64) -> Result<u64, JsError> {
    if value.is_finite() && value >= 0.0 && value.fract() == 0.0 && value <= MAX_SAFE {
        Ok(value as u64)
    } else {
        Err(JsError::new(&format!(
            "seed {value} is not valid: expected an integer in [0, 2^53]"
        )))
    }
}
