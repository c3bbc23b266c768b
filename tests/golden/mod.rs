//! Golden fingerprints shared by the native and the wasm tests (`mod golden;`): the same
//! episode must hash the same on every target.
#![allow(dead_code)]

/// `episode(Action::Grasp, 7, 64)?.digest()`.
pub const GOLDEN_GRASP_SEED7_64: &str =
    "c6cdc56a25998c41b9e7a021c3621c76d666d3495210a1c474b9659a26f891ab";

/// `episode_with_arm(Arm::Panda, Action::Move, 7, 64)?.digest()`: the second arm's episodes
/// are bit-identical on every target too.
pub const GOLDEN_PANDA_MOVE_SEED7_64: &str =
    "bf032448b625feb9288a47ed3e928ac958f0dadfc8d493da79474e23000cff49";

/// `perform` of that episode's own joint rows with its object: the replay's digest.
pub const GOLDEN_PANDA_MOVE_SEED7_REPLAY: &str =
    "e5cb91a0284a96a7e1f54f21948848457a3e7e8a8be554d2dac336a60def473b";
