use serde::{Deserialize, Serialize};

use crate::data::Sequence;
use crate::model::ModelError;
use crate::predict::Predictor;
use crate::quality::{score_sequence, Accumulator, Scenario};

/// Observations of the `interp` scenario, as `dmbn score`'s default.
const INTERP_OBSERVATIONS: usize = 5;
/// Blend of the two modalities, as `dmbn score`'s default.
const BLEND: f32 = 0.5;

/// The quality benchmark on held-out sequences during training: the model's error over the
/// trivial baseline's (< 1 beats it), per scenario and modality. The validation loss keeps
/// falling while the predictions between and beyond the observations get worse (σ shrinks on
/// the steps a model has learned), so the model kept as `best.dmbn` is chosen by this.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ValQuality {
    /// `interp`: joint RMSE over linear interpolation's, image MSE over the nearest frame's.
    pub interp_joint: f32,
    pub interp_image: f32,
    /// `extrap`: joint RMSE and image MSE over holding the last observation's.
    pub extrap_joint: f32,
    pub extrap_image: f32,
    /// `interp`: the object's overlap (IoU) in the predicted frames, not a ratio: whether the
    /// model draws the small object yet (`None` when it is never visible).
    #[serde(default)]
    pub interp_object_iou: Option<f32>,
}

impl ValQuality {
    /// Scores `predictor` on `sequences`; `None` when none is long enough for both scenarios.
    pub fn measure(
        predictor: &Predictor,
        sequences: &[&Sequence],
    ) -> Result<Option<ValQuality>, ModelError> {
        let mut ratios = [[0.0f32; 2]; 2];
        let mut interp_object_iou = None;
        for (row, scenario) in Scenario::ALL.into_iter().enumerate() {
            let (mut model, mut baseline) = (Accumulator::default(), Accumulator::default());
            for seq in sequences {
                let scored = score_sequence(
                    predictor,
                    seq,
                    "",
                    scenario,
                    INTERP_OBSERVATIONS,
                    BLEND,
                    None,
                )?;
                if let Some(scores) = scored {
                    model.merge(&scores.model);
                    baseline.merge(&scores.baseline);
                }
            }
            let (model, baseline) = (model.finish(), baseline.finish());
            if model.steps == 0 {
                return Ok(None);
            }
            if scenario == Scenario::Interp {
                interp_object_iou = model.object_iou.map(|v| v as f32);
            }
            ratios[row] = [
                (model.joint_rmse / baseline.joint_rmse) as f32,
                (model.image_mse / baseline.image_mse) as f32,
            ];
        }
        Ok(Some(ValQuality {
            interp_joint: ratios[0][0],
            interp_image: ratios[0][1],
            extrap_joint: ratios[1][0],
            extrap_image: ratios[1][1],
            interp_object_iou,
        }))
    }

    /// The mean of the four ratios: what `best.dmbn` minimises.
    pub fn score(&self) -> f32 {
        (self.interp_joint + self.interp_image + self.extrap_joint + self.extrap_image) / 4.0
    }
}
