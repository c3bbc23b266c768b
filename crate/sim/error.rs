use thiserror::Error;

/// What can go wrong when setting up a simulation.
#[derive(Debug, Error, PartialEq)]
pub enum SimError {
    #[error("unknown action {0:?}: expected \"grasp\" or \"move\"")]
    UnknownAction(String),
    #[error("image size {0} is not supported: expected 64 or 128")]
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
}
