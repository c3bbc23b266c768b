//! Golden fingerprints shared by the native and the wasm tests (`mod golden;`): the same
//! episode must hash the same on every target.
#![allow(dead_code)]

/// `episode(Action::Grasp, 7, 64)?.digest()`.
pub const GOLDEN_GRASP_SEED7_64: &str =
    "ec2591e28c641877c9137eea8822b8d4651c90809da963e137719bf6d635f4af";
