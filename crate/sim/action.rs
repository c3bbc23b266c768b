use std::fmt;
use std::str::FromStr;

use super::SimError;

/// The two scripted actions of the DMBN dataset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Action {
    /// Approach above the object, descend, close the gripper, lift.
    Grasp,
    /// Push the object across the table (the original's folder name is `move`).
    Move,
}

impl Action {
    /// Both actions, in the order datasets list them.
    pub const ALL: [Action; 2] = [Action::Grasp, Action::Move];

    /// The folder name used in the DMBN layout.
    pub fn name(self) -> &'static str {
        match self {
            Action::Grasp => "grasp",
            Action::Move => "move",
        }
    }
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Action {
    type Err = SimError;
    fn from_str(s: &str) -> Result<Self, SimError> {
        match s {
            "grasp" => Ok(Action::Grasp),
            "move" | "push" => Ok(Action::Move),
            _ => Err(SimError::UnknownAction(s.to_string())),
        }
    }
}
