use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use super::{ActionSummary, Sequence};

/// What `dmbn inspect` reports about a dataset: built one sequence at a time with
/// [`add`](Self::add), so a dataset can be summarised without holding it in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Per action name: count and length range.
    pub actions: BTreeMap<String, ActionSummary>,
    /// Distinct sequence ids.
    pub ids: BTreeSet<u32>,
    /// Per joint column: (min, max) over every step of every sequence (as many as the
    /// dataset's joint values; `dmbn inspect` checks first that every sequence has as many).
    pub joints: Vec<(f32, f32)>,
    /// Names of the joint values, where the dataset's `dataset.json` gives them.
    pub joint_names: Option<Vec<String>>,
    /// Sequences without an `object_<id>.txt` (the object mask, `imitate` need one).
    pub without_object: usize,
    /// Per object coordinate x, y, z: (min, max).
    pub object: [(f32, f32); 3],
    /// Frame size in pixels -> number of sequences with it.
    pub image_sizes: BTreeMap<u32, usize>,
}

impl Default for Summary {
    fn default() -> Self {
        Self::new()
    }
}

impl Summary {
    /// An empty summary.
    pub fn new() -> Self {
        let empty = (f32::INFINITY, f32::NEG_INFINITY);
        Summary {
            actions: BTreeMap::new(),
            ids: BTreeSet::new(),
            joints: Vec::new(),
            joint_names: None,
            without_object: 0,
            object: [empty; 3],
            image_sizes: BTreeMap::new(),
        }
    }

    /// Account for sequence `id` of `action`.
    pub fn add(&mut self, id: u32, action: &str, seq: &Sequence) {
        self.actions
            .entry(action.to_string())
            .or_default()
            .add(seq.len());
        self.ids.insert(id);
        *self.image_sizes.entry(seq.image_size).or_default() += 1;
        if self.joints.is_empty() {
            self.joints = vec![(f32::INFINITY, f32::NEG_INFINITY); seq.joints.width()];
        }
        for row in &seq.joints {
            widen(&mut self.joints, row);
        }
        match &seq.object {
            Some(object) => object.iter().for_each(|row| widen(&mut self.object, row)),
            None => self.without_object += 1,
        }
    }

    /// Number of sequences added.
    pub fn sequences(&self) -> usize {
        self.actions.values().map(|a| a.sequences).sum()
    }
}

fn widen(ranges: &mut [(f32, f32)], row: &[f32]) {
    for (r, &v) in ranges.iter_mut().zip(row) {
        r.0 = r.0.min(v);
        r.1 = r.1.max(v);
    }
}

/// `min .. max` with 4 decimals, `-` when nothing was seen.
fn range(r: (f32, f32)) -> String {
    if r.0 > r.1 {
        "-".into()
    } else {
        format!("{:>8.4} .. {:>8.4}", r.0, r.1)
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sizes: Vec<String> = self
            .image_sizes
            .iter()
            .map(|(s, n)| format!("{s}x{s} ({n} sequences)"))
            .collect();
        writeln!(
            f,
            "{} sequences, {} ids, {} joint values a step, frames {}",
            self.sequences(),
            self.ids.len(),
            self.joints.len(),
            if sizes.is_empty() {
                "-".into()
            } else {
                sizes.join(", ")
            }
        )?;
        writeln!(f)?;
        writeln!(
            f,
            "{:<10} {:>9} {:>8} {:>8} {:>8}",
            "action", "sequences", "min len", "mean len", "max len"
        )?;
        for (name, a) in &self.actions {
            writeln!(
                f,
                "{:<10} {:>9} {:>8} {:>8.1} {:>8}",
                name,
                a.sequences,
                a.min_len,
                a.mean_len(),
                a.max_len
            )?;
        }
        writeln!(f)?;
        writeln!(f, "{:<12} range (min .. max)", "column")?;
        let width = self.joints.len();
        for (j, r) in self.joints.iter().enumerate() {
            let label = match &self.joint_names {
                Some(names) => names[j].clone(),
                None if j + 1 == width && width > 1 => "gripper".to_string(),
                None => format!("joint {j}"),
            };
            writeln!(f, "{label:<12} {}", range(*r))?;
        }
        for (axis, r) in ["x", "y", "z"].iter().zip(&self.object) {
            writeln!(f, "{:<12} {}", format!("object {axis}"), range(*r))?;
        }
        if self.without_object > 0 {
            writeln!(
                f,
                "{} sequences have no object_<id>.txt: no object mask (IoU) or imitation for them",
                self.without_object
            )?;
        }
        Ok(())
    }
}
