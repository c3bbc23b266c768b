//! Golden fingerprints shared by the native and the wasm tests (`mod golden;`): the same
//! episode must hash the same on every target.
#![allow(dead_code)]

/// `episode(Action::Grasp, 7, 64)?.digest()`.
pub const GOLDEN_GRASP_SEED7_64: &str =
    "11b0e85f36f1eb1c3bd78aed7afe2c1ca0529ce7107e97c55f9cde9aa62117fd";
