use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::quality::Scenario;

/// What the model is shown of a demonstration before the arm acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Task {
    /// K evenly spaced frames, no joints (blend 1 by default): imitation from sight alone.
    /// The whole trajectory is the model's.
    Frames,
    /// The first 30% observed at 3 steps, both modalities (blend 0.5 by default): the arm
    /// performs the observed part as recorded and the rest as predicted.
    Finish,
}

/// The steps of one demonstration in a [`Task`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TaskSteps {
    /// Observed step indices, increasing.
    pub observed: Vec<usize>,
    /// The first step performed as predicted; the steps before it are performed as recorded.
    pub predicted_from: usize,
}

impl Task {
    /// Both tasks.
    pub const ALL: [Task; 2] = [Task::Frames, Task::Finish];

    /// `frames` or `finish`.
    pub fn name(self) -> &'static str {
        match self {
            Task::Frames => "frames",
            Task::Finish => "finish",
        }
    }

    /// The blend the task observes with unless told otherwise: frames only, or both alike.
    pub fn default_blend(self) -> f32 {
        match self {
            Task::Frames => 1.0,
            Task::Finish => 0.5,
        }
    }

    /// The steps of a `len`-step demonstration, `observations` (K ≥ 2) evenly spaced for
    /// `frames` (first and last included, as the quality benchmark's `interp`), the first 30%
    /// for `finish` (as its `extrap`). `None` when the demonstration is too short.
    pub fn steps(self, len: usize, observations: usize) -> Option<TaskSteps> {
        match self {
            Task::Frames => Some(TaskSteps {
                observed: Scenario::Interp.steps(len, observations)?.observed,
                predicted_from: 0,
            }),
            Task::Finish => {
                let steps = Scenario::Extrap.steps(len, observations)?;
                Some(TaskSteps {
                    predicted_from: steps.scored[0],
                    observed: steps.observed,
                })
            }
        }
    }
}

impl fmt::Display for Task {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Task {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "frames" => Ok(Task::Frames),
            "finish" => Ok(Task::Finish),
            _ => Err(format!("{s:?} is not a task: expected frames or finish")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_predict_everything_and_finish_only_the_rest() {
        let s = Task::Frames.steps(61, 5).unwrap();
        assert_eq!((s.observed, s.predicted_from), (vec![0, 15, 30, 45, 60], 0));
        let s = Task::Finish.steps(61, 5).unwrap();
        assert_eq!((s.observed, s.predicted_from), (vec![0, 9, 18], 19));
        assert!(Task::Frames.steps(4, 5).is_none());
        assert_eq!("finish".parse::<Task>(), Ok(Task::Finish));
        assert!("interp"
            .parse::<Task>()
            .unwrap_err()
            .contains("frames or finish"));
    }
}
