use rand::RngExt;
use rand_pcg::Pcg64;
use serde::{Deserialize, Serialize};

use super::AugmentError;
use crate::data::{Joints, Sequence};

/// The paper's training augmentation (§3.2): change the speed of random sections of a
/// sequence and insert repeated frames (freezes), so that a frame's content stops telling its
/// time exactly. The warped sequence is a re-timing of the original: every step is one of the
/// original steps, in non-decreasing order, and its time is its phase in the new sequence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeWarpConfig {
    /// Probability that a sequence is warped at all.
    pub probability: f64,
    /// Number of sections whose speed changes, drawn uniformly from this range (inclusive).
    pub sections: [usize; 2],
    /// Length of each section as a fraction of the sequence, drawn uniformly.
    pub section_fraction: [f64; 2],
    /// Speed factor of each section (2 = twice as fast, half the frames), drawn log-uniformly.
    pub speed: [f64; 2],
    /// Probability of inserting a freeze (a step repeated).
    pub freeze_probability: f64,
    /// Extra copies of the frozen step, drawn uniformly from this range (inclusive).
    pub freeze_length: [usize; 2],
    /// If set, the freeze's length is instead drawn as a fraction of the warped sequence
    /// (uniformly from this range, below 1): the paper's freezes "of any length", up to most
    /// of the action, which a count of copies cannot express for sequences of any length.
    #[serde(default)]
    pub freeze_fraction: Option<[f64; 2]>,
}

impl Default for TimeWarpConfig {
    fn default() -> Self {
        TimeWarpConfig {
            probability: 0.8,
            sections: [1, 3],
            section_fraction: [0.1, 0.4],
            speed: [0.5, 2.0],
            freeze_probability: 0.5,
            freeze_length: [3, 15],
            freeze_fraction: None,
        }
    }
}

impl TimeWarpConfig {
    /// Checks every range: ordered, probabilities in [0, 1], fractions in (0, 1], speeds > 0.
    pub fn validate(&self) -> Result<(), AugmentError> {
        let bad = |field, value: String, expected: &str| AugmentError::TimeWarp {
            field,
            value,
            expected: expected.to_string(),
        };
        for (field, p) in [
            ("probability", self.probability),
            ("freeze_probability", self.freeze_probability),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(bad(field, p.to_string(), "a probability in [0, 1]"));
            }
        }
        let ranges = [
            ("sections", self.sections.map(|n| n as f64), 0.0),
            ("section_fraction", self.section_fraction, 0.0),
            ("speed", self.speed, f64::MIN_POSITIVE),
            ("freeze_length", self.freeze_length.map(|n| n as f64), 0.0),
        ];
        for (field, [lo, hi], min) in ranges {
            if !(lo.is_finite() && hi.is_finite() && min <= lo && lo <= hi) {
                let expected = format!("finite bounds, {min} <= low <= high");
                return Err(bad(field, format!("[{lo}, {hi}]"), &expected));
            }
        }
        if let Some([lo, hi]) = self.freeze_fraction {
            if !(0.0..1.0).contains(&lo) || !(lo..1.0).contains(&hi) {
                let expected = "0 <= low <= high < 1 (a fraction of the warped sequence)";
                return Err(bad("freeze_fraction", format!("[{lo}, {hi}]"), expected));
            }
        }
        let [a, b] = self.section_fraction;
        if a <= 0.0 || b > 1.0 {
            return Err(bad(
                "section_fraction",
                format!("[{a}, {b}]"),
                "fractions in (0, 1]",
            ));
        }
        Ok(())
    }

    /// The step indices of a warped version of a `len`-step sequence: non-decreasing, each in
    /// `0..len`, first 0 and last `len - 1` (the action still starts and ends), at least 2 long
    /// when `len >= 2`. Deterministic for a given `rng` state.
    pub fn indices(&self, len: usize, rng: &mut Pcg64) -> Vec<usize> {
        if len < 3 || !rng.random_bool(self.probability) {
            return (0..len).collect();
        }
        // Source position (in original steps) of every output step.
        let mut speed = vec![1.0f64; len];
        for _ in 0..rng.random_range(self.sections[0]..=self.sections[1]) {
            let fraction = rng.random_range(self.section_fraction[0]..=self.section_fraction[1]);
            let width = ((fraction * len as f64).round() as usize).clamp(1, len);
            let start = rng.random_range(0..=len - width);
            let (lo, hi) = (self.speed[0].ln(), self.speed[1].ln());
            let factor = rng.random_range(lo..=hi).exp();
            speed[start..start + width].fill(factor);
        }
        let last = (len - 1) as f64;
        let mut indices = Vec::with_capacity(2 * len);
        let mut position = 0.0f64;
        while position < last {
            indices.push(position.round() as usize);
            position += speed[position.round() as usize];
        }
        indices.push(len - 1);
        if rng.random_bool(self.freeze_probability) {
            let at = rng.random_range(0..indices.len());
            let copies = match self.freeze_fraction {
                // A freeze of `copies` extra steps covers copies / (n + copies) of the result.
                Some([lo, hi]) => {
                    let fraction = rng.random_range(lo..=hi);
                    (fraction / (1.0 - fraction) * indices.len() as f64).round() as usize
                }
                None => rng.random_range(self.freeze_length[0]..=self.freeze_length[1]),
            };
            let step = indices[at];
            indices.splice(at..at, std::iter::repeat_n(step, copies));
        }
        indices
    }

    /// A warped copy of `seq` (see [`TimeWarpConfig::indices`]).
    pub fn apply(&self, seq: &Sequence, rng: &mut Pcg64) -> Sequence {
        gather(seq, &self.indices(seq.len(), rng))
    }
}

/// The sequence made of `seq`'s steps `indices` (every index below `seq.len()`).
pub fn gather(seq: &Sequence, indices: &[usize]) -> Sequence {
    Sequence {
        image_size: seq.image_size,
        joints: Joints::from_slices(seq.joints.width(), indices.iter().map(|&k| &seq.joints[k])),
        endpoint: seq
            .endpoint
            .as_ref()
            .map(|e| indices.iter().map(|&k| e[k]).collect()),
        object: seq
            .object
            .as_ref()
            .map(|o| indices.iter().map(|&k| o[k]).collect()),
        frames: indices
            .iter()
            .flat_map(|&k| seq.frame(k))
            .copied()
            .collect(),
    }
}
