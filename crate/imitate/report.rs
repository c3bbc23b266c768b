use std::fmt::Write;

use serde::Serialize;

use crate::sim::{Action, PushMiss};

use super::imitation::joint_rmse;
use super::{Imitation, Task};

/// One row's performances of one action, summed over demonstrations.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OutcomeSums {
    episodes: usize,
    successes: usize,
    // Every performance's value: a row reports medians (a pushed object that falls off the
    // table ends metres away, which a mean would report as the row's error).
    lift_cm: Vec<f32>,
    object_error_cm: Vec<f32>,
    path_error_cm: Vec<f32>,
    misses: PushMisses,
    /// Per arm joint (as many as the performances' arm has; none before the first).
    joint_se: Vec<f64>,
    joint_steps: usize,
}

impl OutcomeSums {
    /// Counts one performance.
    pub fn add(&mut self, imitation: &Imitation) {
        let o = &imitation.outcome;
        self.episodes += 1;
        self.successes += usize::from(o.success);
        self.lift_cm.push(o.lift_cm);
        self.object_error_cm.push(o.object_error_cm);
        self.path_error_cm.push(o.path_error_cm);
        if let (false, Some(e)) = (o.success, o.push_error_cm) {
            self.misses.add(e.miss());
        }
        if self.joint_se.len() < imitation.joint_se.len() {
            self.joint_se.resize(imitation.joint_se.len(), 0.0);
        }
        for (sum, se) in self.joint_se.iter_mut().zip(&imitation.joint_se) {
            *sum += se;
        }
        self.joint_steps += imitation.joint_steps;
    }

    /// Performances counted.
    pub fn episodes(&self) -> usize {
        self.episodes
    }

    /// The row `name` of `action`, with its success rate against `ceiling`'s where given.
    pub fn row(&self, name: &str, action: &str, ceiling: Option<&OutcomeSums>) -> ImitationRow {
        let n = self.episodes.max(1) as f64;
        let rate = self.successes as f64 / n;
        let of_ceiling = ceiling
            .filter(|c| c.successes > 0)
            .map(|c| rate / (c.successes as f64 / c.episodes as f64));
        ImitationRow {
            name: name.to_string(),
            action: action.to_string(),
            episodes: self.episodes,
            successes: self.successes,
            success_rate: rate,
            of_ceiling,
            lift_cm: median(&self.lift_cm),
            object_error_cm: median(&self.object_error_cm),
            path_error_cm: median(&self.path_error_cm),
            push_misses: (action == Action::Move.name()).then_some(self.misses),
            joint_rmse: joint_rmse(
                self.joint_se.iter().sum(),
                self.joint_steps * self.joint_se.len(),
            ),
            joint_rmse_per_joint: self
                .joint_se
                .iter()
                .map(|&se| joint_rmse(se, self.joint_steps))
                .collect(),
        }
    }
}

/// The missed pushes of a row, by how they missed ([`PushMiss`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct PushMisses {
    /// Pushed too little.
    pub short: usize,
    /// Pushed too far.
    pub long: usize,
    /// Knocked aside.
    pub aside: usize,
}

impl PushMisses {
    fn add(&mut self, miss: PushMiss) {
        *match miss {
            PushMiss::Short => &mut self.short,
            PushMiss::Long => &mut self.long,
            PushMiss::Aside => &mut self.aside,
        } += 1;
    }
}

/// The median of `values` (the mean of the middle two for an even count; 0 for none).
fn median(values: &[f32]) -> f64 {
    let mut v: Vec<f64> = values.iter().map(|&x| f64::from(x)).collect();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// One model's (or the ceiling's, or the floor's) performances of one action.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImitationRow {
    /// The model file, `ceiling: recorded joints` or `floor: mean motion`.
    pub name: String,
    /// `grasp` or `move`.
    pub action: String,
    /// Demonstrations performed.
    pub episodes: usize,
    /// Performances that succeeded (see [`Outcome`](crate::sim::Outcome)).
    pub successes: usize,
    /// `successes / episodes`.
    pub success_rate: f64,
    /// The success rate over the ceiling's (absent for a ceiling that never succeeded).
    pub of_ceiling: Option<f64>,
    /// Median final height of the object above its resting height, cm.
    pub lift_cm: f64,
    /// Median distance of the object's final position to the demonstration's, cm.
    pub object_error_cm: f64,
    /// Median over performances of the grasp point's mean distance to the demonstration's, cm.
    pub path_error_cm: f64,
    /// Pushes: the missed ones by how they missed (absent for grasps).
    pub push_misses: Option<PushMisses>,
    /// RMSE of the performed trajectory's arm joints against the demonstration's, at the
    /// steps it predicted (radians; 0 for the ceiling).
    pub joint_rmse: f64,
    /// The same per arm joint, base to wrist (which joint a model reads or moves worst).
    pub joint_rmse_per_joint: Vec<f64>,
}

/// `dmbn imitate`'s result for one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImitationReport {
    pub task: Task,
    /// Observations per demonstration (`frames`; `finish` observes 3 in the first 30%).
    pub observations: usize,
    /// Blending coefficient (1 = frames only).
    pub blend: f32,
    /// Per action: the ceiling, the floor (when fitted), then each model.
    pub rows: Vec<ImitationRow>,
}

impl ImitationReport {
    /// A Markdown table of the rows.
    pub fn table(&self) -> String {
        let mut out = format!(
            "task {} ({} observations, blend {}):\n\n| action | trajectory | episodes | success | of ceiling | lift (cm, median) | object error (cm, median) | path error (cm, median) | misses: short / long / aside | joint RMSE (rad) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
            self.task,
            match self.task {
                Task::Frames => self.observations,
                Task::Finish => crate::quality::Scenario::EXTRAP_OBSERVATIONS,
            },
            self.blend
        );
        for r in &self.rows {
            let of = r
                .of_ceiling
                .map_or("—".to_string(), |v| format!("{:.0}%", v * 100.0));
            let misses = r.push_misses.map_or("—".to_string(), |m| {
                format!("{} / {} / {}", m.short, m.long, m.aside)
            });
            let _ = writeln!(
                out,
                "| {} | {} | {} | {}/{} ({:.0}%) | {of} | {:.1} | {:.2} | {:.2} | {misses} | {:.3} |",
                r.action,
                r.name,
                r.episodes,
                r.successes,
                r.episodes,
                r.success_rate * 100.0,
                r.lift_cm,
                r.object_error_cm,
                r.path_error_cm,
                r.joint_rmse
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_ignore_one_object_off_the_table() {
        assert_eq!(median(&[1.0, -900.0, 3.0]), 1.0);
        assert_eq!(median(&[1.0, 2.0, 3.0, 10.0]), 2.5);
        assert_eq!(median(&[]), 0.0);
    }
}
