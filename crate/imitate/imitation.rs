use super::joint_noise::joint_noise;
use super::task::TaskSteps;
use super::{ImitateError, Task};
use crate::data::{Joints, Sequence};
use crate::predict::{Observations, Predictor};
use crate::quality::MeanMotion;
use crate::sim::{perform, Action, Arm, Outcome, Trajectory};

/// One performance of a demonstration's action: the trajectory the arm was given, what it
/// did, and how that went.
#[derive(Debug, Clone, PartialEq)]
pub struct Imitation {
    /// The trajectory performed, one row per step of the demonstration, as wide as the
    /// demonstration's joints (its width names the arm that performed it).
    pub trajectory: Vec<Vec<f32>>,
    /// The recorded performance (frames, reached joints, object track).
    pub performance: Sequence,
    /// Judged against the demonstration.
    pub outcome: Outcome,
    /// The demonstration's steps the model observed (none for a replay).
    pub observed: Vec<usize>,
    /// The first step performed from the trajectory's own rows rather than the recording.
    pub predicted_from: usize,
    /// Squared error of each arm joint (radians²) summed over the steps from
    /// `predicted_from` on, against the demonstration's recorded joints.
    pub joint_se: Vec<f64>,
    /// How many steps `joint_se` sums over.
    pub joint_steps: usize,
}

impl Imitation {
    /// Root mean squared error of the trajectory's arm joints at its own steps (radians).
    pub fn joint_rmse(&self) -> f64 {
        joint_rmse(
            self.joint_se.iter().sum(),
            self.joint_steps * self.joint_se.len(),
        )
    }
}

/// The RMSE of `values` squared errors summed in `se` (0 for none).
pub(super) fn joint_rmse(se: f64, values: usize) -> f64 {
    (se / values.max(1) as f64).sqrt()
}

/// `predictor` imitates `demo` (an episode of `action`): it observes the `task`'s steps
/// (`observations` for `frames`) with blend `blend`, predicts the joint means at every step,
/// and the arm performs them (after the observed part as recorded, for `finish`) with the
/// object where the demonstration had it. `Ok(None)` when the demonstration is too short.
pub fn imitate(
    predictor: &Predictor,
    demo: &Sequence,
    action: Action,
    task: Task,
    observations: usize,
    blend: f32,
) -> Result<Option<Imitation>, ImitateError> {
    let Some(steps) = task.steps(demo.len(), observations) else {
        return Ok(None);
    };
    let observed = Observations::from_sequence(demo, &steps.observed)?;
    let times = demo.times();
    let predicted = predictor.predict_joints(&observed, &times[steps.predicted_from..], blend)?;
    Ok(Some(act(demo, action, steps, arm_rows(&predicted)?)?))
}

/// The ceiling: the demonstration's own recorded joints performed.
pub fn replay(demo: &Sequence, action: Action) -> Result<Imitation, ImitateError> {
    enact(demo, action, arm_rows(&demo.joints)?, Vec::new())
}

/// The arm performs `rows`, one per step of `demo` (joint means a model predicted from the
/// demonstration's `observed` steps elsewhere: the page's workers), with the object where the
/// demonstration had it, judged against it. The rows are as wide as the demonstration's.
pub fn enact(
    demo: &Sequence,
    action: Action,
    rows: Vec<impl AsRef<[f32]>>,
    observed: Vec<usize>,
) -> Result<Imitation, ImitateError> {
    let steps = TaskSteps {
        observed,
        predicted_from: 0,
    };
    let rows = rows.iter().map(|r| r.as_ref().to_vec()).collect();
    act(demo, action, steps, rows)
}

/// The floor: the action's mean motion performed (after the observed part as recorded, for
/// `finish`), what a model that ignores what it saw would do at best. `Ok(None)` when the
/// demonstration is too short for the task.
pub fn mean_motion(
    demo: &Sequence,
    action: Action,
    task: Task,
    observations: usize,
    mean: &MeanMotion,
) -> Result<Option<Imitation>, ImitateError> {
    unobserved(demo, action, task, observations, |from| {
        let mut rows = Joints::with_width(demo.joints.width());
        for &phase in &demo.times()[from..] {
            let (_, joints) = mean.at(action.name(), phase).ok_or_else(|| {
                ImitateError::Invalid(format!(
                    "the mean motion has no {action} sequence: fit it on sequences of every action imitated"
                ))
            })?;
            rows.push(&joints);
        }
        arm_rows(&rows)
    })
}

/// The demonstration's recorded joints with smooth noise of RMSE `rmse` radians ([`joint_noise`],
/// drawn from `seed`) on the arm joints from the task's first predicted step on, performed:
/// how much error of a model's kind the action tolerates. `Ok(None)` when the demonstration is
/// too short for the task.
pub fn with_noise(
    demo: &Sequence,
    action: Action,
    task: Task,
    observations: usize,
    rmse: f32,
    seed: u64,
) -> Result<Option<Imitation>, ImitateError> {
    unobserved(demo, action, task, observations, |from| {
        let recorded = arm_rows(&demo.joints)?;
        let arm_joints = demo.joints.width() - 1;
        let noise = joint_noise(demo.len() - from, arm_joints, rmse, seed);
        Ok(recorded[from..]
            .iter()
            .zip(noise)
            .map(|(row, noise)| {
                let mut row = row.clone();
                row.iter_mut().zip(noise).for_each(|(v, n)| *v += n);
                row
            })
            .collect())
    })
}

/// A trajectory that observed nothing (the floor, the noisy replays) performed for `task`: the
/// recorded rows before the task's first predicted step, then `rows(that step)`. `Ok(None)`
/// when the demonstration is too short for the task.
fn unobserved(
    demo: &Sequence,
    action: Action,
    task: Task,
    observations: usize,
    rows: impl FnOnce(usize) -> Result<Vec<Vec<f32>>, ImitateError>,
) -> Result<Option<Imitation>, ImitateError> {
    let Some(steps) = task.steps(demo.len(), observations) else {
        return Ok(None);
    };
    let rows = rows(steps.predicted_from)?;
    let steps = TaskSteps {
        observed: Vec::new(),
        ..steps
    };
    Ok(Some(act(demo, action, steps, rows)?))
}

/// Performs the demonstration's recorded rows before `steps.predicted_from`, then `rows`,
/// with the object where the demonstration had it at its first step, and judges the result.
pub(super) fn act(
    demo: &Sequence,
    action: Action,
    steps: TaskSteps,
    rows: Vec<Vec<f32>>,
) -> Result<Imitation, ImitateError> {
    let from = steps.predicted_from;
    let recorded = arm_rows(&demo.joints)?;
    let Some(object) = demo.object.as_ref().and_then(|o| o.first()) else {
        return Err(ImitateError::Invalid(
            "the demonstration has no object track (object_<id>.txt): imitation places the \
             simulator's object where the demonstration had it, so it needs simulator data"
                .into(),
        ));
    };
    if demo.is_empty() || rows.len() + from != demo.len() {
        return Err(ImitateError::Invalid(format!(
            "{} trajectory rows after {from} recorded ones for a demonstration of {} steps: \
             expected one row per step",
            rows.len(),
            demo.len()
        )));
    }
    let width = demo.joints.width();
    if let Some(row) = rows.iter().find(|r| r.len() != width) {
        return Err(ImitateError::Invalid(format!(
            "a trajectory row of {} values for a demonstration of {width} a step: expected rows \
             as wide as the demonstration's",
            row.len()
        )));
    }
    let trajectory: Vec<Vec<f32>> = recorded[..from].iter().cloned().chain(rows).collect();
    let joints = Joints::from_slices(width, trajectory.iter().map(Vec::as_slice));
    let performance = perform(
        &Trajectory::of_joints(joints)?,
        [object[0], object[1]],
        demo.image_size,
    )?;
    let outcome = Outcome::judge(action, &performance, demo)
        .ok_or_else(|| ImitateError::Invalid("an empty demonstration".into()))?;
    let mut joint_se = vec![0.0; width - 1];
    for (a, b) in trajectory[from..].iter().zip(&recorded[from..]) {
        for (j, se) in joint_se.iter_mut().enumerate() {
            *se += (a[j] as f64 - b[j] as f64).powi(2);
        }
    }
    Ok(Imitation {
        trajectory,
        performance,
        outcome,
        observed: steps.observed,
        predicted_from: from,
        joint_se,
        joint_steps: demo.len() - from,
    })
}

/// `joints` as one of the simulator's arms takes them (its angles, then the gripper: 7 values
/// a step the UR5, 8 the Panda): imitation performs the arm the width names, so data of
/// another robot is refused, saying so.
pub(super) fn arm_rows(joints: &Joints) -> Result<Vec<Vec<f32>>, ImitateError> {
    if Arm::of_width(joints.width()).is_err() {
        return Err(ImitateError::Invalid(format!(
            "the trajectory has {} joint values a step: imitation performs the simulator's arms, \
             which take {} (the angles, then the gripper): imitate needs the simulator's data \
             and a model trained on it",
            joints.width(),
            Arm::widths_text()
        )));
    }
    Ok(joints.rows().map(<[f32]>::to_vec).collect())
}
