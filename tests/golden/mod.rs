//! Golden fingerprints shared by the native and the wasm tests (`mod golden;`): the same
//! episode must hash the same on every target.
#![allow(dead_code)]

/// `episode(Action::Grasp, 7, 64)?.digest()`.
pub const GOLDEN_GRASP_SEED7_64: &str =
    "c6cdc56a25998c41b9e7a021c3621c76d666d3495210a1c474b9659a26f891ab";
