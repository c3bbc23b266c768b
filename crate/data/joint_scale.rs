use serde::{Deserialize, Serialize};

/// How the joint normalisation scales the six arm angles. The loss is a (β-)NLL in normalised
/// units, so the scale decides how much a radian of each joint counts: standardised per
/// joint, a wrist that sweeps ±3 rad weighs as little per radian as an elbow that moves
/// 0.3; with one shared scale a radian counts the same on every joint — the unit the quality
/// benchmark's joint RMSE is in. The gripper column keeps its own scale either way.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JointScale {
    /// Each column divided by its own standard deviation.
    #[default]
    PerJoint,
    /// The six arm angles divided by one standard deviation: the root mean square of theirs.
    Shared,
}
