use wasm_bindgen::{JsError, JsValue};

use crate::sim::Action;

/// A JS value as an action name. Taken as a `JsValue` rather than `&str` because the generated
/// glue does not check types in release builds: a non-string would corrupt memory instead of
/// throwing.
pub(crate) fn parse_action(value: &JsValue) -> Result<Action, JsError> {
    match value.as_string() {
        Some(name) => Ok(name.parse()?),
        None => Err(JsError::new(&format!(
            "action must be a string (\"grasp\" or \"move\"), got {value:?}"
        ))),
    }
}
