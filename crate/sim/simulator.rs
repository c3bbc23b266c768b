use crate::data::Sequence;

use super::{Action, SimError};

/// A running episode: physics world, scripted controller and renderer.
pub struct Simulator {}

impl Simulator {
    /// Region (metres, arm-base frame: x right, y away from the camera) where objects are placed.
    pub const REGION: ([f32; 2], [f32; 2]) = ([-0.15, 0.15], [0.45, 0.65]);

    /// An episode of `action` with the object placed from `seed`; frames `image_size` (64 or 128).
    pub fn new(action: Action, seed: u64, image_size: u32) -> Result<Self, SimError> {
        let _ = (action, seed, image_size);
        todo!()
    }

    /// An episode with the object at `(x, y)` on the table; `seed` still varies the timing.
    pub fn with_object(action: Action, x: f32, y: f32, seed: u64, image_size: u32) -> Result<Self, SimError> {
        let _ = (action, x, y, seed, image_size);
        todo!()
    }

    /// Number of recorded steps the episode will have.
    pub fn len(&self) -> usize { todo!() }
    /// Index of the current step (0 after construction).
    pub fn step_index(&self) -> usize { todo!() }
    /// Advance one recorded step; false (and no change) when the episode is over.
    pub fn step(&mut self) -> bool { todo!() }
    /// Joint values at the current step (6 angles, gripper).
    pub fn joints(&self) -> [f32; 7] { todo!() }
    /// End effector xyz, orientation, gripper at the current step.
    pub fn endpoint(&self) -> [f32; 7] { todo!() }
    /// Object xyz at the current step.
    pub fn object(&self) -> [f32; 3] { todo!() }
    /// Frame size in pixels.
    pub fn image_size(&self) -> u32 { todo!() }
    /// RGB frame of the current step, `image_size² × 3` bytes.
    pub fn frame(&self) -> Vec<u8> { todo!() }
    /// Record the whole (remaining) episode, current step included.
    pub fn run(self) -> Sequence { todo!() }
}

/// Generate one whole episode.
pub fn episode(action: Action, seed: u64, image_size: u32) -> Result<Sequence, SimError> {
    Ok(Simulator::new(action, seed, image_size)?.run())
}
