use crate::augment::{EvalMode, EvalSequence};
use crate::model::ModelError;
use crate::predict::{Observations, Predictor, Scores, SequencePrediction};

/// One evaluation: the shown sequence, which of its steps were observed, the prediction at
/// every step's time stamp and its scores against the shown sequence.
#[derive(Debug, Clone)]
pub struct Evaluation {
    pub mode: EvalMode,
    pub shown: EvalSequence,
    pub observed: Vec<usize>,
    pub blend: f32,
    pub prediction: SequencePrediction,
    pub scores: Scores,
}

/// `k` step indices spread evenly over `0..len`, first and last included (k ≥ 2), distinct.
pub fn evenly_spaced(len: usize, k: usize) -> Vec<usize> {
    let k = k.min(len);
    match k {
        0 => Vec::new(),
        1 => vec![0],
        _ => (0..k)
            .map(|i| (i as f64 * (len - 1) as f64 / (k - 1) as f64).round() as usize)
            .collect(),
    }
}

/// Observes `observed` steps of `shown` (frames, joints and their time stamps), predicts every
/// step at its time stamp and scores the prediction against what was shown.
pub fn evaluate(
    predictor: &Predictor,
    mode: EvalMode,
    shown: EvalSequence,
    observed: Vec<usize>,
    blend: f32,
) -> Result<Evaluation, ModelError> {
    let seq = &shown.sequence;
    let mut observations = Observations::from_sequence(seq, &observed)?;
    observations.times = observed.iter().map(|&k| shown.times[k]).collect();
    let prediction = predictor.predict(&observations, &shown.times, blend)?;
    let scores = Scores::of(
        &prediction,
        &seq.frames,
        &seq.joints,
        predictor.normalization(),
    )
    .ok_or_else(|| ModelError::observation("targets", "prediction and sequence lengths differ"))?;
    Ok(Evaluation {
        mode,
        shown,
        observed,
        blend,
        prediction,
        scores,
    })
}
