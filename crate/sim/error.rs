use thiserror::Error;

use super::Action;
use crate::data::DataError;

/// What can go wrong when setting up a simulation or generating a dataset.
#[derive(Debug, Error)]
pub enum SimError {
    #[error("unknown action {0:?}: expected \"grasp\" or \"move\"")]
    UnknownAction(String),
    #[error("unknown arm {0:?}: expected {arms}", arms = super::Arm::names_text())]
    UnknownArm(String),
    #[error(
        "rows of {0} joint values a step: the simulator's arms take {widths} (the angles, then the gripper)",
        widths = super::Arm::widths_text()
    )]
    ArmWidth(usize),
    #[error(
        "image size {0} is not supported: expected {sizes}",
        sizes = crate::data::image_sizes_text()
    )]
    ImageSize(u32),
    #[error("object position ({x}, {y}) is outside the placement region x in [{x0}, {x1}], y in [{y0}, {y1}]")]
    ObjectOutOfRegion {
        x: f32,
        y: f32,
        x0: f32,
        x1: f32,
        y0: f32,
        y1: f32,
    },
    #[error("sequence {id} ({action}, seed {seed}): {source}")]
    Sequence {
        id: u32,
        action: Action,
        seed: u64,
        #[source]
        source: Box<SimError>,
    },
    #[error("no sequences to generate: expected at least one id and one action")]
    NothingToGenerate,
    #[error("action {0} is listed twice: expected each action once")]
    DuplicateAction(Action),
    #[error("only {written} of {total} sequences were generated")]
    Incomplete { written: usize, total: usize },
    #[error("trajectory {0}")]
    Trajectory(String),
    #[error(transparent)]
    Data(#[from] DataError),
}
