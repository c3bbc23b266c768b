//! The robot-arm simulator: an arm on a table with one object, driven through scripted grasp
//! and move (push) actions, recorded as [`Sequence`](crate::data::Sequence)s, one at a time or
//! (natively) as a whole dataset on worker threads (`generate`). Two arms ([`Arm`]) carry the
//! same gripper: a UR-like 6-joint arm (the default) and a Panda-like 7-joint one; the code
//! is generic over the joint count ([`Chain`]).
//!
//! Physics is rapier3d (multibody joints with position motors, `enhanced-determinism`), the
//! frames come from a small ray caster; both are bit-identical natively and in wasm.
mod action;
mod arm;
mod chain;
mod error;
#[cfg(not(target_arch = "wasm32"))]
mod generate;
mod ik;
mod outcome;
mod panda;
mod plan;
mod push_error;
mod push_miss;
mod render;
mod rig;
mod scene;
mod script;
mod simulator;
mod trajectory;
mod ur5;

pub use action::Action;
pub use arm::Arm;
pub use chain::{Chain, FINGER_OPEN, FINGER_TRAVEL, GRASP_DEPTH};
pub use error::SimError;
#[cfg(not(target_arch = "wasm32"))]
pub use generate::{generate, generate_with_arm};
pub use ik::{GripperPose, Ik};
pub use outcome::Outcome;
pub use panda::PANDA;
pub use plan::{Plan, GRIPPER_CLOSED, GRIPPER_OPEN};
pub use push_error::PushError;
pub use push_miss::PushMiss;
pub use render::{Camera, Primitive, Renderer, Shape};
pub use scene::{Scene, OBJECT_HALF_HEIGHT, OBJECT_RADIUS, SUBSTEPS};
pub use script::{Script, Segment};
pub use simulator::{episode, episode_with_arm, perform, Simulator};
pub use trajectory::Trajectory;
pub use ur5::UR5;
