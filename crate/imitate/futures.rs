use std::fmt::Write;

use serde::Serialize;

use super::imitation::act;
use super::{ImitateError, Imitation, Task};
use crate::data::Sequence;
use crate::futures::{sample_trajectories, Sampling};
use crate::predict::{Observations, Predictor};
use crate::sim::Action;

/// `predictor` imagines S futures of `demo` (an episode of `action`) from the `task`'s
/// observations ([`crate::futures`]), and the arm performs each (after the observed part as
/// recorded, for `finish`), with the object where the demonstration had it. `Ok(None)` when
/// the demonstration is too short for the task.
pub fn imitate_futures(
    predictor: &Predictor,
    demo: &Sequence,
    action: Action,
    task: Task,
    observations: usize,
    blend: f32,
    sampling: &Sampling,
) -> Result<Option<Vec<Imitation>>, ImitateError> {
    let Some(steps) = task.steps(demo.len(), observations) else {
        return Ok(None);
    };
    let observed = Observations::from_sequence(demo, &steps.observed)?;
    let future = &demo.times()[steps.predicted_from..];
    let trajectories = sample_trajectories(predictor, &observed, future, future, blend, sampling)?;
    trajectories
        .iter()
        .map(|rows| {
            act(
                demo,
                action,
                steps.clone(),
                super::imitation::arm_rows(rows)?,
            )
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Some)
}

/// One model's sampled futures of one action, counted over demonstrations.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FutureSums {
    demonstrations: usize,
    performed: usize,
    valid: usize,
    covered: usize,
    mean_valid: usize,
    mean_successes: usize,
}

impl FutureSums {
    /// Counts one demonstration's performed `futures` and its single-mean `mean` performance.
    pub fn add(&mut self, futures: &[Imitation], mean: &Imitation) {
        self.demonstrations += 1;
        self.performed += futures.len();
        self.valid += futures.iter().filter(|f| f.outcome.valid).count();
        self.covered += usize::from(futures.iter().any(|f| f.outcome.success));
        self.mean_valid += usize::from(mean.outcome.valid);
        self.mean_successes += usize::from(mean.outcome.success);
    }

    /// The row `name` of `action`, its coverage against the ceiling's success rate
    /// `ceiling_rate` where given.
    pub fn row(&self, name: &str, action: &str, ceiling_rate: Option<f64>) -> FuturesRow {
        let rate = |k: usize, n: usize| k as f64 / n.max(1) as f64;
        let coverage = rate(self.covered, self.demonstrations);
        FuturesRow {
            name: name.to_string(),
            action: action.to_string(),
            demonstrations: self.demonstrations,
            performed: self.performed,
            validity: rate(self.valid, self.performed),
            coverage,
            coverage_of_ceiling: ceiling_rate.filter(|&c| c > 0.0).map(|c| coverage / c),
            mean_validity: rate(self.mean_valid, self.demonstrations),
            mean_success: rate(self.mean_successes, self.demonstrations),
        }
    }
}

/// Sampled futures performed: how many were valid actions, and for how many demonstrations
/// one of them succeeded, beside the single mean's performance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FuturesRow {
    /// The model file.
    pub name: String,
    /// `grasp` or `move`.
    pub action: String,
    /// Demonstrations imagined.
    pub demonstrations: usize,
    /// Futures performed (S per demonstration).
    pub performed: usize,
    /// Share of the performed futures that are a valid action ([`crate::sim::Outcome::valid`]).
    pub validity: f64,
    /// Share of demonstrations for which at least one future succeeded.
    pub coverage: f64,
    /// Coverage over the ceiling's success rate.
    pub coverage_of_ceiling: Option<f64>,
    /// The single mean's performances: the share valid...
    pub mean_validity: f64,
    /// ...and the share that succeeded.
    pub mean_success: f64,
}

/// `dmbn imitate --samples`'s result for one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FuturesReport {
    pub task: Task,
    pub sampling: Sampling,
    pub rows: Vec<FuturesRow>,
}

impl FuturesReport {
    /// A Markdown table of the rows.
    pub fn table(&self) -> String {
        let s = &self.sampling;
        let mut out = format!(
            "task {}, {} sampled futures each ({}):\n\n| action | model | demonstrations | validity | coverage | of ceiling | single mean: valid | single mean: success |\n|---|---|---:|---:|---:|---:|---:|---:|\n",
            self.task,
            s.samples,
            s.describe()
        );
        let pc = |v: f64| format!("{:.0}%", v * 100.0);
        for r in &self.rows {
            let of = r.coverage_of_ceiling.map_or("—".to_string(), pc);
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {of} | {} | {} |",
                r.action,
                r.name,
                r.demonstrations,
                pc(r.validity),
                pc(r.coverage),
                pc(r.mean_validity),
                pc(r.mean_success)
            );
        }
        out
    }
}
