//! JS values as Rust arguments. Every exported function takes its plain arguments as
//! `JsValue` and converts them here, because the generated glue does not check them in release
//! builds: a `&str` given a number corrupts memory (a trap), a `u32` given `null` or `[]`
//! silently becomes 0. Here any JS value either converts or becomes an `Error` naming the
//! parameter, what was expected and what came. (Class handles are checked by the glue itself:
//! "expected instance of Episode"; a freed one by wasm-bindgen's null check.)
use std::str::FromStr;

use js_sys::{Array, Float32Array, Reflect, Uint32Array, Uint8Array, Uint8ClampedArray};
use wasm_bindgen::{JsCast, JsError, JsValue};

use super::region::Region;
use crate::data::MAX_IMAGE_SIZE;
use crate::sim::Action;

/// Largest integer a JS number holds exactly (`Number.MAX_SAFE_INTEGER`): larger ones alias
/// their neighbours, so the same number would not always mean the same seed.
pub(crate) const MAX_SAFE: u64 = (1 << 53) - 1;

/// The error for parameter `name`: "`name` must be `expected`, got …".
pub(crate) fn wrong(name: &str, expected: &str, value: &JsValue) -> JsError {
    JsError::new(&format!(
        "{name} must be {expected}, got {}",
        describe(value)
    ))
}

/// A short description of any JS value for an error message (long strings by their length).
pub(crate) fn describe(value: &JsValue) -> String {
    if value.is_undefined() {
        return "undefined".into();
    }
    if value.is_null() {
        return "null".into();
    }
    if let Some(n) = value.as_f64() {
        return format!("the number {}", number_text(n));
    }
    if let Some(b) = value.as_bool() {
        return b.to_string();
    }
    if let Some(s) = value.as_string() {
        return match s.chars().count() {
            0..=40 => format!("{s:?}"),
            n => format!("a string of {n} characters"),
        };
    }
    if Array::is_array(value) {
        return format!("an array of {} items", Array::from(value).length());
    }
    if value.is_object() {
        let name = Reflect::get(value, &"constructor".into())
            .and_then(|c| Reflect::get(&c, &"name".into()))
            .ok()
            .and_then(|n| n.as_string())
            .filter(|n| !n.is_empty());
        return match name {
            Some(name) => format!("an object ({name})"),
            None => "an object".into(),
        };
    }
    value
        .js_typeof()
        .as_string()
        .unwrap_or_else(|| "a value".into())
}

/// A number as JS writes it (`NaN`, `Infinity`, `-1`, `0.5`).
fn number_text(n: f64) -> String {
    match n {
        n if n.is_nan() => "NaN".into(),
        f64::INFINITY => "Infinity".into(),
        f64::NEG_INFINITY => "-Infinity".into(),
        n => n.to_string(),
    }
}

/// A string argument, any content.
pub(crate) fn string(value: &JsValue, name: &str) -> Result<String, JsError> {
    value
        .as_string()
        .ok_or_else(|| wrong(name, "a string", value))
}

/// A string argument naming one of a few choices (an action, a mode, a scenario, a task),
/// parsed as `T`; `expected` lists them ("\"grasp\" or \"move\"").
pub(crate) fn choice<T: FromStr>(
    value: &JsValue,
    name: &str,
    expected: &str,
) -> Result<T, JsError> {
    value
        .as_string()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| wrong(name, expected, value))
}

/// A finite number in `[min, max]`.
pub(crate) fn number(value: &JsValue, name: &str, min: f64, max: f64) -> Result<f64, JsError> {
    match value.as_f64() {
        Some(n) if n.is_finite() && (min..=max).contains(&n) => Ok(n),
        _ => {
            let expected = match (min, max) {
                (f64::MIN, f64::MAX) => "a finite number".to_string(),
                (min, f64::MAX) if min > 0.0 => "a finite number above 0".to_string(),
                (min, f64::MAX) => format!("a finite number from {min}"),
                (min, max) => format!("a number in [{min}, {max}]"),
            };
            Err(wrong(name, &expected, value))
        }
    }
}

/// An integer from `min` to `max` (inclusive; at most [`MAX_SAFE`]).
pub(crate) fn integer(value: &JsValue, name: &str, min: u64, max: u64) -> Result<u64, JsError> {
    match value.as_f64() {
        Some(n) if n.fract() == 0.0 && (min as f64..=max as f64).contains(&n) => Ok(n as u64),
        _ => Err(wrong(
            name,
            &format!("an integer from {min} to {max}"),
            value,
        )),
    }
}

/// An index (an integer from 0 to 2^32 - 1), as `usize`.
pub(crate) fn index(value: &JsValue, name: &str) -> Result<usize, JsError> {
    integer(value, name, 0, u64::from(u32::MAX)).map(|i| i as usize)
}

/// [`index`], or `None` for `undefined` and `null` (an omitted argument).
pub(crate) fn optional_index(value: &JsValue, name: &str) -> Result<Option<usize>, JsError> {
    if value.is_undefined() || value.is_null() {
        return Ok(None);
    }
    let expected = "an integer from 0 to 4294967295, or undefined";
    index(value, name)
        .map(Some)
        .map_err(|_| wrong(name, expected, value))
}

/// A `Uint8Array` (or `Uint8ClampedArray`, as canvas `ImageData` holds) copied into wasm.
pub(crate) fn bytes(value: &JsValue, name: &str) -> Result<Vec<u8>, JsError> {
    if let Some(a) = value.dyn_ref::<Uint8Array>() {
        Ok(a.to_vec())
    } else if let Some(a) = value.dyn_ref::<Uint8ClampedArray>() {
        Ok(a.to_vec())
    } else {
        Err(wrong(name, "a Uint8Array", value))
    }
}

/// A `Float32Array` copied into wasm.
pub(crate) fn floats(value: &JsValue, name: &str) -> Result<Vec<f32>, JsError> {
    value
        .dyn_ref::<Float32Array>()
        .map(Float32Array::to_vec)
        .ok_or_else(|| wrong(name, "a Float32Array", value))
}

/// A `Uint32Array` of indices copied into wasm.
pub(crate) fn indices(value: &JsValue, name: &str) -> Result<Vec<usize>, JsError> {
    let Some(a) = value.dyn_ref::<Uint32Array>() else {
        return Err(wrong(name, "a Uint32Array", value));
    };
    Ok(a.to_vec().into_iter().map(|i| i as usize).collect())
}

/// An array of strings.
pub(crate) fn strings(value: &JsValue, name: &str) -> Result<Vec<String>, JsError> {
    if !Array::is_array(value) {
        return Err(wrong(name, "an array of strings", value));
    }
    Array::from(value)
        .iter()
        .enumerate()
        .map(|(i, item)| string(&item, &format!("{name}[{i}]")))
        .collect()
}

/// `action`: `"grasp"` or `"move"`.
pub(crate) fn action(value: &JsValue) -> Result<Action, JsError> {
    choice(value, "action", "\"grasp\" or \"move\"")
}

/// `seed`: an integer the same in JS and Rust, from 0 to 2^53 - 1.
pub(crate) fn seed(value: &JsValue) -> Result<u64, JsError> {
    integer(value, "seed", 0, MAX_SAFE)
}

/// `imageSize`: frame width and height in pixels (the simulator and models then ask for 64
/// or 128; a folder is resized to any size up to the reader's limit).
pub(crate) fn image_size(value: &JsValue) -> Result<u32, JsError> {
    integer(value, "imageSize", 1, u64::from(MAX_IMAGE_SIZE)).map(|n| n as u32)
}

/// `blend`: in [0, 1] (1 = images only, 0 = joints only).
pub(crate) fn blend(value: &JsValue) -> Result<f32, JsError> {
    number(value, "blend", 0.0, 1.0).map(|b| b as f32)
}

/// `observations`: a count of observed steps, from 2 to 10,000.
pub(crate) fn observations(value: &JsValue) -> Result<usize, JsError> {
    integer(value, "observations", 2, 10_000).map(|n| n as usize)
}

/// `x`, `y`: an object position in metres inside `placementRegion()`.
pub(crate) fn position(x: &JsValue, y: &JsValue) -> Result<[f32; 2], JsError> {
    let region = Region::new();
    Ok([
        number(x, "x", region.x[0], region.x[1])? as f32,
        number(y, "y", region.y[0], region.y[1])? as f32,
    ])
}
