#[cfg(doc)]
use super::Script;
use super::Trajectory;

/// Where every episode starts: above the middle of the placement region.
pub const HOME: [f32; 3] = [0.0, 0.52, 0.40];
/// A performed trajectory's gripper column (the fingers' total travel, negative) above which
/// the gripper is commanded open (see [`Plan::from_trajectory`]).
pub const GRIPPER_OPEN: f32 = -0.03;
/// ... and below which it is commanded fully closed.
pub const GRIPPER_CLOSED: f32 = -0.06;

/// The scripted trajectory of one episode of an arm of `N` joints (the UR5's 6 unless said):
/// per recorded step, the joint targets the motors track and the gripper closure (0 open,
/// 1 fully closed).
#[derive(Debug, Clone, PartialEq)]
pub struct Plan<const N: usize = 6> {
    /// Arm joint targets per step.
    pub joints: Vec<[f32; N]>,
    /// Gripper closure target per step, in [0, 1].
    pub closure: Vec<f32>,
}

impl<const N: usize> Plan<N> {
    /// The motor targets that make the arm perform `trajectory` (rows of `N` angles and the
    /// gripper: the caller picks `N` by the trajectory's arm): its rows' angles, and the
    /// gripper commanded closed as the gripper column closes, read one step ahead (the
    /// fingers reach a closure a step after it is commanded). The column is the fingers'
    /// measured travel, not a command: an open gripper's leading finger is pushed in by up
    /// to about a centimetre when it pushes the object, and fingers closed on the object stop
    /// at about -0.09. So the closure is 0 up to [`GRIPPER_OPEN`], 1 from [`GRIPPER_CLOSED`]
    /// (the full closure squeezes, however far the fingers got), linear between.
    ///
    /// Replaying a recorded episode's joints so reproduces its outcome (the simulator's
    /// tests): the arm is deflected a little by contacts when recorded and again when
    /// replayed, which costs millimetres; a target lead to make up for the motors' lag only
    /// moved the path further from the recording (measured).
    pub fn from_trajectory(trajectory: &Trajectory) -> Plan<N> {
        let rows = trajectory.joints();
        assert_eq!(rows.width(), N + 1, "a trajectory of another arm");
        let last = rows.len() - 1;
        let joints = rows.rows().map(|r| std::array::from_fn(|i| r[i])).collect();
        let closure = (0..rows.len())
            .map(|k| {
                let gripper = rows.row((k + 1).min(last))[N];
                ((gripper - GRIPPER_OPEN) / (GRIPPER_CLOSED - GRIPPER_OPEN)).clamp(0.0, 1.0)
            })
            .collect();
        Plan { joints, closure }
    }

    /// Number of recorded steps.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// True for a plan without steps (never produced by [`Script::plan`]).
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}
