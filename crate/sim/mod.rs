//! The robot-arm simulator: a UR-like arm on a table with one object, driven through
//! scripted grasp and move (push) actions, recorded as [`Sequence`](crate::data::Sequence)s.
mod action;
mod error;
mod simulator;

pub use action::Action;
pub use error::SimError;
pub use simulator::{episode, Simulator};
