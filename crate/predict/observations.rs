use crate::data::Sequence;
use crate::model::ModelError;

/// What the model is shown: N context steps of one sequence, both modalities at the same
/// steps, in the units of a dataset (RGB bytes, joint angles in radians, phase in [0, 1]).
#[derive(Debug, Clone, PartialEq)]
pub struct Observations {
    /// S: frame width and height.
    pub image_size: usize,
    /// `N × S × S × 3` bytes: RGB frames, rows top to bottom (as [`Sequence::frames`]).
    pub frames: Vec<u8>,
    /// `N × D`: joint values, not normalised.
    pub joints: Vec<f32>,
    /// `N`: the phase of each observed step.
    pub times: Vec<f32>,
}

impl Observations {
    /// Steps `steps` of `seq`; fails on an empty set or a step past the end.
    pub fn from_sequence(seq: &Sequence, steps: &[usize]) -> Result<Self, ModelError> {
        if let Some(&step) = steps.iter().find(|&&k| k >= seq.len()) {
            return Err(ModelError::observation(
                "steps",
                format!(
                    "contains {step}: expected step indices below the sequence's {} steps",
                    seq.len()
                ),
            ));
        }
        let times = seq.times();
        let obs = Observations {
            image_size: seq.image_size as usize,
            frames: steps.iter().flat_map(|&k| seq.frame(k)).copied().collect(),
            joints: steps
                .iter()
                .flat_map(|&k| seq.joints[k].iter().copied())
                .collect(),
            times: steps.iter().map(|&k| times[k]).collect(),
        };
        obs.check(obs.image_size, seq.joints.width())?;
        Ok(obs)
    }

    /// N: observed steps.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True when nothing is observed (never valid input).
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Checks the set against a model for `image_size` frames and `d` joint values a step: at
    /// least one context, and frames, joints and times of matching lengths with finite values
    /// and times in [0, 1].
    pub fn check(&self, image_size: usize, d: usize) -> Result<(), ModelError> {
        let n = self.len();
        if n == 0 {
            return Err(ModelError::observation(
                "times",
                "is empty: expected at least one observed step",
            ));
        }
        if self.image_size != image_size {
            return Err(ModelError::ImageSize {
                expected: image_size,
                found: self.image_size,
            });
        }
        let frame = image_size * image_size * 3;
        if self.frames.len() != n * frame {
            return Err(ModelError::observation(
                "frames",
                format!(
                    "holds {} bytes, expected {n} frames × {image_size}×{image_size}×3 = {} (RGB at the model's frame size)",
                    self.frames.len(),
                    n * frame
                ),
            ));
        }
        if self.joints.len() != n * d {
            return Err(ModelError::observation(
                "joints",
                format!(
                    "holds {} values, expected {n} steps × {d} = {} (the model's {d} joint values a step)",
                    self.joints.len(),
                    n * d
                ),
            ));
        }
        if let Some(v) = self.joints.iter().find(|v| !v.is_finite()) {
            return Err(ModelError::observation(
                "joints",
                format!("contains {v}: expected finite values"),
            ));
        }
        if let Some(t) = self.times.iter().find(|t| !(0.0..=1.0).contains(*t)) {
            return Err(ModelError::observation(
                "times",
                format!("contains {t}: expected phases in [0, 1]"),
            ));
        }
        Ok(())
    }
}
