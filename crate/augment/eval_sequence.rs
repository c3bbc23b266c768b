use rand::seq::SliceRandom;
use rand_pcg::Pcg64;

use super::time_warp::gather;
use super::AugmentError;
use crate::data::Sequence;

/// The paper's evaluation sequences (§3, "Model Evaluation"): what a model is shown, and the
/// time stamp of every step. Targets are the shown sequence itself: a model that understands time follows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvalMode {
    /// `t`: the sequence unchanged.
    Unchanged,
    /// `p`: the time stamps permuted among the frames (frames stay in order).
    Permuted,
    /// `f`: one step shown for a section of the sequence, or for all of it.
    Frozen,
}

impl std::str::FromStr for EvalMode {
    type Err = AugmentError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "t" => Ok(EvalMode::Unchanged),
            "p" => Ok(EvalMode::Permuted),
            "f" => Ok(EvalMode::Frozen),
            _ => Err(AugmentError::Mode {
                found: s.to_string(),
            }),
        }
    }
}

impl EvalMode {
    /// The mode's letter, as in the paper and on the command line.
    pub fn letter(self) -> &'static str {
        match self {
            EvalMode::Unchanged => "t",
            EvalMode::Permuted => "p",
            EvalMode::Frozen => "f",
        }
    }
}

/// A sequence with explicit time stamps (which need not be its phases).
#[derive(Debug, Clone, PartialEq)]
pub struct EvalSequence {
    /// What is shown at every step.
    pub sequence: Sequence,
    /// The time stamp of every step.
    pub times: Vec<f32>,
}

impl EvalSequence {
    /// `t`: `seq` with its phases.
    pub fn unchanged(seq: &Sequence) -> Self {
        EvalSequence {
            sequence: seq.clone(),
            times: seq.times(),
        }
    }

    /// `p`: the phases of `seq` shuffled among its steps.
    pub fn permuted(seq: &Sequence, rng: &mut Pcg64) -> Self {
        let mut times = seq.times();
        times.shuffle(rng);
        EvalSequence {
            sequence: seq.clone(),
            times,
        }
    }

    /// `f`: steps `from..to` all show step `from` (the arm and camera stand still there), with
    /// the original phases. `frozen(seq, 0, seq.len())` freezes the whole sequence on its first
    /// frame. `from..to` is clamped to the sequence.
    pub fn frozen(seq: &Sequence, from: usize, to: usize) -> Self {
        let len = seq.len();
        let to = to.min(len);
        let from = from.min(to.saturating_sub(1));
        let indices: Vec<usize> = (0..len)
            .map(|k| if (from..to).contains(&k) { from } else { k })
            .collect();
        EvalSequence {
            sequence: gather(seq, &indices),
            times: seq.times(),
        }
    }

    /// The evaluation sequence of `mode` (`f` freezes `freeze`, default the whole sequence).
    pub fn build(
        mode: EvalMode,
        seq: &Sequence,
        freeze: Option<(usize, usize)>,
        rng: &mut Pcg64,
    ) -> Self {
        match mode {
            EvalMode::Unchanged => Self::unchanged(seq),
            EvalMode::Permuted => Self::permuted(seq, rng),
            EvalMode::Frozen => {
                let (from, to) = freeze.unwrap_or((0, seq.len()));
                Self::frozen(seq, from, to)
            }
        }
    }
}
