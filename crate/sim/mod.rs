//! The robot-arm simulator: a UR-like arm on a table with one object, driven through
//! scripted grasp and move (push) actions, recorded as [`Sequence`](crate::data::Sequence)s,
//! one at a time or (natively) as a whole dataset on worker threads (`generate`).
//!
//! Physics is rapier3d (multibody joints with position motors, `enhanced-determinism`), the
//! frames come from a small ray caster; both are bit-identical natively and in wasm.
mod action;
mod arm;
mod error;
#[cfg(not(target_arch = "wasm32"))]
mod generate;
mod ik;
mod outcome;
mod plan;
mod push_error;
mod push_miss;
mod render;
mod scene;
mod script;
mod simulator;
mod trajectory;

pub use action::Action;
pub use arm::Arm;
pub use error::SimError;
#[cfg(not(target_arch = "wasm32"))]
pub use generate::generate;
pub use ik::{GripperPose, Ik};
pub use outcome::Outcome;
pub use plan::{Plan, GRIPPER_CLOSED, GRIPPER_OPEN};
pub use push_error::PushError;
pub use push_miss::PushMiss;
pub use render::{Camera, Primitive, Renderer, Shape};
pub use scene::{Scene, OBJECT_HALF_HEIGHT, OBJECT_RADIUS, SUBSTEPS};
pub use script::{Script, Segment};
pub use simulator::{episode, perform, Simulator};
pub use trajectory::Trajectory;
