use super::panda::PANDA;
use super::ur5::UR5;
use super::{Arm, SimError};
use crate::data::Joints;

/// A joint trajectory for an arm to perform, one row per recorded step (20 per second): the
/// arm's joint angles in radians, then the gripper value in the data's convention (0 open,
/// negative while closing): the rows of a `joint_<id>.txt`, or a model's predicted joint means.
/// The rows' width names the arm ([`Arm::of_width`]: 7 values the UR5, 8 the Panda).
///
/// The rows are what the arm should *reach* at each step, as the data files record them; the
/// simulator turns them into motor targets ([`Plan::from_trajectory`](super::Plan::from_trajectory)).
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    arm: Arm,
    joints: Joints,
}

impl Trajectory {
    /// The longest trajectory performed: 100 seconds (the scripted actions take 2-6).
    pub const MAX_STEPS: usize = 2000;

    /// A trajectory of `rows` (their width names the arm); fails as [`Trajectory::of_joints`].
    pub fn new<const W: usize>(rows: Vec<[f32; W]>) -> Result<Trajectory, SimError> {
        Trajectory::of_joints(Joints::from_rows(&rows))
    }

    /// A trajectory of `joints`; fails on a width no arm has, no row, more than
    /// [`Trajectory::MAX_STEPS`], a value that is not finite or an arm angle beyond its
    /// joint's limit.
    pub fn of_joints(joints: Joints) -> Result<Trajectory, SimError> {
        let arm = Arm::of_width(joints.width())?;
        if joints.is_empty() {
            return Err(SimError::Trajectory(format!(
                "has no rows: expected at least one step of {} values",
                arm.width()
            )));
        }
        if joints.len() > Self::MAX_STEPS {
            return Err(SimError::Trajectory(format!(
                "has {} steps: expected at most {}",
                joints.len(),
                Self::MAX_STEPS
            )));
        }
        let limits: &[f32] = match arm {
            Arm::Ur5 => &UR5.limits,
            Arm::Panda => &PANDA.limits,
        };
        for (k, row) in joints.rows().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if !v.is_finite() {
                    return Err(SimError::Trajectory(format!(
                        "row {k}, column {j} is {v}: expected a finite number"
                    )));
                }
                if let Some(&limit) = limits.get(j).filter(|&&limit| v.abs() > limit) {
                    return Err(SimError::Trajectory(format!(
                        "row {k}, joint {j} is {v} rad: expected an angle within ±{limit} (the {arm}'s joint limits)"
                    )));
                }
            }
        }
        Ok(Trajectory { arm, joints })
    }

    /// A UR5 trajectory from `T × 7` values, step-major (as `Episode.joints()` gives them in wasm).
    pub fn from_flat(values: &[f32]) -> Result<Trajectory, SimError> {
        Trajectory::from_flat_on(Arm::Ur5, values)
    }

    /// `arm`'s trajectory from `T × width` values, step-major.
    pub fn from_flat_on(arm: Arm, values: &[f32]) -> Result<Trajectory, SimError> {
        let width = arm.width();
        match Joints::new(width, values.to_vec()) {
            Some(joints) => Trajectory::of_joints(joints),
            None => Err(SimError::Trajectory(format!(
                "has {} values: expected T rows of {width} ({} joint angles of the {arm}, the gripper)",
                values.len(),
                arm.joints()
            ))),
        }
    }

    /// The arm the rows are for.
    pub fn arm(&self) -> Arm {
        self.arm
    }

    /// The rows, one per step.
    pub fn joints(&self) -> &Joints {
        &self.joints
    }

    /// Number of steps.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Always false: a trajectory has at least one step.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;

    #[test]
    fn bad_trajectories_are_refused_with_what_was_expected() {
        let err = |r: Result<Trajectory, SimError>| r.unwrap_err().to_string();
        assert!(err(Trajectory::new(Vec::<[f32; JOINTS]>::new())).contains("no rows"));
        assert!(err(Trajectory::from_flat(&[0.0; 13])).contains("13 values"));
        let mut row = [0.0; JOINTS];
        row[2] = f32::NAN;
        assert!(err(Trajectory::new(vec![[0.0; JOINTS], row])).contains("row 1, column 2 is NaN"));
        row[2] = 7.0;
        assert!(err(Trajectory::new(vec![row])).contains("joint 2 is 7 rad"));
        row[2] = 0.0;
        row[6] = f32::INFINITY;
        assert!(err(Trajectory::new(vec![row])).contains("column 6 is inf"));
        let long = vec![[0.0; JOINTS]; Trajectory::MAX_STEPS + 1];
        assert!(err(Trajectory::new(long)).contains("at most 2000"));
        let ok = Trajectory::from_flat(&[0.5; 14]).unwrap();
        assert_eq!((ok.len(), ok.arm()), (2, Arm::Ur5));
        assert_eq!(ok.joints().row(1), [0.5; JOINTS]);
    }

    #[test]
    fn the_rows_width_names_the_arm_and_its_limits() {
        let err = |r: Result<Trajectory, SimError>| r.unwrap_err().to_string();
        let panda = Trajectory::new(vec![[0.5f32; 8]; 3]).unwrap();
        assert_eq!((panda.len(), panda.arm()), (3, Arm::Panda));
        assert_eq!(
            Trajectory::from_flat_on(Arm::Panda, &[0.5; 24]).unwrap(),
            panda
        );
        let e = err(Trajectory::new(vec![[0.0f32; 9]]));
        assert!(
            e.contains("9 joint values") && e.contains("7 (ur5) or 8 (panda)"),
            "{e}"
        );
        // The Panda's shoulder pitch stops at 1.76 rad, the UR5's at 2π.
        let mut row = [0.0f32; 8];
        row[1] = 2.0;
        assert!(err(Trajectory::new(vec![row])).contains("joint 1 is 2 rad"));
        assert!(Trajectory::new(vec![[2.0f32; 7]]).is_ok());
        assert!(err(Trajectory::from_flat_on(Arm::Panda, &[0.0; 14])).contains("rows of 8"));
    }
}
