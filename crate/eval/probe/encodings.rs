//! The probe's data: every step of some sequences encoded as a one-context set.
use burn::tensor::Device;

use crate::augment::Batch;
use crate::data::{Normalization, Sequence};
use crate::model::{tensors, values, Model, ModelError};

/// Every step of some sequences encoded as a single context, per modality: the probe's data.
#[derive(Debug, Clone, PartialEq)]
pub struct StepEncodings {
    /// H: encoding width.
    pub hidden: usize,
    /// `K × H`: image context encodings.
    pub image: Vec<f32>,
    /// `K × H`: joint context encodings.
    pub joint: Vec<f32>,
    /// `K`: the true time (phase) of every step.
    pub times: Vec<f32>,
}

/// Steps encoded per forward pass.
const ENCODE_CHUNK: usize = 64;

/// Encodes every step of `seqs` as a one-context set with `model`'s encoders (DMBN: e_m(t, x);
/// DMBN-PTE: g_m(e_m(x) + P(t))), joints normalised with `normalization`. With `zero_time`
/// the encoders are fed t = 0 instead of the step's time (the probe's Null row); the
/// returned `times` are always the true ones.
pub fn encode_steps(
    model: &Model,
    normalization: &Normalization,
    seqs: &[Sequence],
    zero_time: bool,
) -> Result<StepEncodings, ModelError> {
    let device = Device::flex();
    let s = model.image_size();
    let steps: Vec<(&Sequence, usize, f32)> = seqs
        .iter()
        .flat_map(|seq| {
            let times = seq.times();
            (0..seq.len()).map(move |k| (seq, k, times[k]))
        })
        .collect();
    let mut out = StepEncodings {
        hidden: 0,
        image: Vec::new(),
        joint: Vec::new(),
        times: Vec::new(),
    };
    for chunk in steps.chunks(ENCODE_CHUNK) {
        let b = chunk.len();
        let mut batch = Batch::contexts_only(b, 1, 1, s, normalization.width());
        batch.blend.fill(0.5);
        for (i, &(seq, k, t)) in chunk.iter().enumerate() {
            let time = if zero_time { 0.0 } else { t };
            batch.set_context(
                i,
                0,
                seq.frame(k),
                &normalization.normalize(&seq.joints[k]),
                time,
            );
            out.times.push(t);
        }
        let z = model.encode_contexts(&tensors(&batch, &device)?)?;
        out.hidden = z.image.dims()[2];
        out.image.extend(values(z.image));
        out.joint.extend(values(z.joint));
    }
    Ok(out)
}
