use super::arm::ARM_JOINTS;
use super::{Arm, SimError};
use crate::data::JOINTS;

/// A joint trajectory for the arm to perform, one row per recorded step (20 per second): six
/// arm joint angles in radians, then the gripper value in the data's convention (0 open,
/// negative while closing): the rows of a `joint_<id>.txt`, or a model's predicted joint means.
///
/// The rows are what the arm should *reach* at each step, as the data files record them; the
/// simulator turns them into motor targets ([`Plan::from_trajectory`](super::Plan::from_trajectory)).
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    rows: Vec<[f32; JOINTS]>,
}

impl Trajectory {
    /// The longest trajectory performed: 100 seconds (the scripted actions take 2-6).
    pub const MAX_STEPS: usize = 2000;

    /// A trajectory of `rows`; fails on no row, more than [`Trajectory::MAX_STEPS`], a value
    /// that is not finite or an arm angle beyond the joints' limits (±2π).
    pub fn new(rows: Vec<[f32; JOINTS]>) -> Result<Trajectory, SimError> {
        if rows.is_empty() {
            return Err(SimError::Trajectory(
                "has no rows: expected at least one step of 7 values".into(),
            ));
        }
        if rows.len() > Self::MAX_STEPS {
            return Err(SimError::Trajectory(format!(
                "has {} steps: expected at most {}",
                rows.len(),
                Self::MAX_STEPS
            )));
        }
        for (k, row) in rows.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if !v.is_finite() {
                    return Err(SimError::Trajectory(format!(
                        "row {k}, column {j} is {v}: expected a finite number"
                    )));
                }
                if j < ARM_JOINTS && v.abs() > Arm::LIMIT {
                    return Err(SimError::Trajectory(format!(
                        "row {k}, joint {j} is {v} rad: expected an angle within ±{} (the joint limits)",
                        Arm::LIMIT
                    )));
                }
            }
        }
        Ok(Trajectory { rows })
    }

    /// A trajectory from `T × 7` values, step-major (as `Episode.joints()` gives them in wasm).
    pub fn from_flat(values: &[f32]) -> Result<Trajectory, SimError> {
        if values.len() % JOINTS != 0 {
            return Err(SimError::Trajectory(format!(
                "has {} values: expected T rows of {JOINTS} (6 joint angles, the gripper)",
                values.len()
            )));
        }
        let rows = values
            .chunks_exact(JOINTS)
            .map(|r| std::array::from_fn(|j| r[j]))
            .collect();
        Trajectory::new(rows)
    }

    /// The rows, one per step.
    pub fn rows(&self) -> &[[f32; JOINTS]] {
        &self.rows
    }

    /// Number of steps.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Always false: a trajectory has at least one step.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_trajectories_are_refused_with_what_was_expected() {
        let err = |r: Result<Trajectory, SimError>| r.unwrap_err().to_string();
        assert!(err(Trajectory::new(vec![])).contains("no rows"));
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
        assert_eq!(ok.len(), 2);
        assert_eq!(ok.rows()[1], [0.5; JOINTS]);
    }
}
