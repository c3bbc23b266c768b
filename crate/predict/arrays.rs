//! A prediction with the observations it was made from, as safetensors: what `dmbn predict
//! --arrays` writes, so that another implementation (python/dmbn_torch `check`) can
//! predict from the same inputs and compare every value.
use std::collections::HashMap;

use safetensors::tensor::TensorView;
use safetensors::Dtype;

use super::{Observations, SequencePrediction};
use crate::model::ModelError;

/// The safetensors bytes of `prediction`, made from `observations` with blending coefficient
/// `blend`: `observed_frames` (u8 `[N, S, S, 3]`), `observed_joints` `[N, D]`,
/// `observed_times` `[N]`, `blend` `[1]`, `target_times` `[T]`, `image_mean` and
/// `image_sigma` `[T, S, S, 3]`, `joint_mean` and `joint_sigma` `[T, D]` (dataset units, as
/// [`SequencePrediction`]).
pub fn prediction_arrays(
    observations: &Observations,
    blend: f32,
    prediction: &SequencePrediction,
) -> Result<Vec<u8>, ModelError> {
    let (n, t, s, d) = (
        observations.len(),
        prediction.len(),
        prediction.image_size,
        prediction.joints,
    );
    let f32s = |name, shape, v: &[f32]| {
        let bytes = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        (name, Dtype::F32, shape, bytes)
    };
    let frames = observations.frames.clone();
    let arrays: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
        ("observed_frames", Dtype::U8, vec![n, s, s, 3], frames),
        f32s("observed_joints", vec![n, d], &observations.joints),
        f32s("observed_times", vec![n], &observations.times),
        f32s("blend", vec![1], &[blend]),
        f32s("target_times", vec![t], &prediction.times),
        f32s("image_mean", vec![t, s, s, 3], &prediction.image_mean),
        f32s("image_sigma", vec![t, s, s, 3], &prediction.image_sigma),
        f32s("joint_mean", vec![t, d], &prediction.joint_mean),
        f32s("joint_sigma", vec![t, d], &prediction.joint_sigma),
    ];
    let views = arrays
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            TensorView::new(*dtype, shape.clone(), bytes).map(|view| (*name, view))
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| ModelError::Safetensors(format!("cannot write the arrays: {e}")))?;
    let metadata = HashMap::from([("producer".to_string(), "dmbn predict".to_string())]);
    safetensors::serialize(views, Some(metadata))
        .map_err(|e| ModelError::Safetensors(format!("cannot write the arrays: {e}")))
}
