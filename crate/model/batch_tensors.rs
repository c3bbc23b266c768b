use burn::tensor::{Device, Tensor, TensorData};

use super::ModelError;
use crate::augment::{Batch, JointTargets};

/// A [`Batch`] as tensors on one device, checked: every length matches the stated sizes,
/// every value is finite, the mask holds only 0 and 1, every sequence has a context and every
/// blending coefficient lies in [0, 1]. Built by [`tensors`].
#[derive(Debug, Clone)]
pub struct BatchTensors {
    /// S: frame width and height.
    pub image_size: usize,
    /// `[B, N, 3, S, S]`: context frames, RGB in [0, 1].
    pub context_images: Tensor<5>,
    /// `[B, N, D]`: context joints, normalised.
    pub context_joints: Tensor<3>,
    /// `[B, N]`: context times (phase).
    pub context_times: Tensor<2>,
    /// `[B, N]`: 1 for a real context, 0 for padding.
    pub context_mask: Tensor<2>,
    /// `[B, M]`: target times.
    pub target_times: Tensor<2>,
    /// `[B, M, 3, S, S]`: target frames, when the batch has them (training, evaluation).
    pub target_images: Option<Tensor<5>>,
    /// `[B, M, D]`: target joints, normalised, when the batch has them.
    pub target_joints: Option<Tensor<3>>,
    /// `[B]`: blending coefficient c of each sequence.
    pub blend: Tensor<1>,
}

impl BatchTensors {
    /// B: sequences in the batch.
    pub fn batch(&self) -> usize {
        self.blend.dims()[0]
    }

    /// N: context slots per sequence.
    pub fn contexts(&self) -> usize {
        self.context_mask.dims()[1]
    }

    /// M: targets per sequence.
    pub fn targets(&self) -> usize {
        self.target_times.dims()[1]
    }
}

/// Checks a [`Batch`] and turns it into tensors on `device`. Bad batches (a wrong length,
/// a zero size, a non-finite value, a mask value other than 0/1, a sequence without any
/// context, a blend outside [0, 1]) give a [`ModelError`] naming the field.
///
/// Target frames and joints may both be empty (inference: only target times are known).
pub fn tensors(batch: &Batch, device: &Device) -> Result<BatchTensors, ModelError> {
    let (b, n, m, s, d) = (
        batch.batch,
        batch.contexts,
        batch.targets,
        batch.image_size,
        batch.joints,
    );
    for (field, value) in [
        ("batch", b),
        ("contexts", n),
        ("targets", m),
        ("image_size", s),
        ("joints", d),
    ] {
        if value == 0 {
            return Err(ModelError::EmptyDimension { field });
        }
    }
    let image = format!("[B={b}, N={n}, 3, S={s}, S={s}]");
    let target_image = format!("[B={b}, M={m}, 3, S={s}, S={s}]");
    check(
        "context_images",
        &batch.context_images,
        b * n * 3 * s * s,
        &image,
    )?;
    check(
        "context_joints",
        &batch.context_joints,
        b * n * d,
        &format!("[B={b}, N={n}, D={d}]"),
    )?;
    check(
        "context_times",
        &batch.context_times,
        b * n,
        &format!("[B={b}, N={n}]"),
    )?;
    check(
        "context_mask",
        &batch.context_mask,
        b * n,
        &format!("[B={b}, N={n}]"),
    )?;
    check(
        "target_times",
        &batch.target_times,
        b * m,
        &format!("[B={b}, M={m}]"),
    )?;
    check("blend", &batch.blend, b, &format!("[B={b}]"))?;
    let has_target_images = !batch.target_images.is_empty();
    if has_target_images {
        check(
            "target_images",
            &batch.target_images,
            b * m * 3 * s * s,
            &target_image,
        )?;
    }
    let has_target_joints = !batch.target_joints.is_empty();
    if has_target_joints {
        check(
            "target_joints",
            &batch.target_joints,
            b * m * d,
            &format!("[B={b}, M={m}, D={d}]"),
        )?;
    }

    for (index, &value) in batch.context_mask.iter().enumerate() {
        if value != 0.0 && value != 1.0 {
            return Err(ModelError::MaskValue { index, value });
        }
    }
    for (sequence, row) in batch.context_mask.chunks(n).enumerate() {
        if !row.contains(&1.0) {
            return Err(ModelError::EmptyContext { sequence });
        }
    }
    for (sequence, &value) in batch.blend.iter().enumerate() {
        if !(0.0..=1.0).contains(&value) {
            return Err(ModelError::Blend { sequence, value });
        }
    }

    Ok(BatchTensors {
        image_size: s,
        context_images: tensor(&batch.context_images, [b, n, 3, s, s], device),
        context_joints: tensor(&batch.context_joints, [b, n, d], device),
        context_times: tensor(&batch.context_times, [b, n], device),
        context_mask: tensor(&batch.context_mask, [b, n], device),
        target_times: tensor(&batch.target_times, [b, m], device),
        target_images: has_target_images
            .then(|| tensor(&batch.target_images, [b, m, 3, s, s], device)),
        target_joints: has_target_joints.then(|| tensor(&batch.target_joints, [b, m, d], device)),
        blend: tensor(&batch.blend, [b], device),
    })
}

/// Checks joint-only targets of `d` values a step and turns them into `[B, M_j]` times and
/// `[B, M_j, D]` joints.
pub fn joint_target_tensors(
    targets: &JointTargets,
    d: usize,
    device: &Device,
) -> Result<(Tensor<2>, Tensor<3>), ModelError> {
    let (b, m) = (targets.batch, targets.targets);
    if b == 0 || m == 0 {
        return Err(ModelError::EmptyDimension {
            field: "joint_targets",
        });
    }
    check(
        "joint_target_times",
        &targets.times,
        b * m,
        &format!("[B={b}, M={m}]"),
    )?;
    check(
        "joint_target_joints",
        &targets.joints,
        b * m * d,
        &format!("[B={b}, M={m}, D={d}]"),
    )?;
    Ok((
        tensor(&targets.times, [b, m], device),
        tensor(&targets.joints, [b, m, d], device),
    ))
}

/// A checked field as a tensor of `shape`.
fn tensor<const D: usize>(values: &[f32], shape: [usize; D], device: &Device) -> Tensor<D> {
    Tensor::from_data(TensorData::new(values.to_vec(), shape), device)
}

/// Checks one field's length and that every value is finite.
fn check(
    field: &'static str,
    values: &[f32],
    expected: usize,
    shape: &str,
) -> Result<(), ModelError> {
    if values.len() != expected {
        return Err(ModelError::Length {
            field,
            expected,
            found: values.len(),
            shape: shape.to_string(),
        });
    }
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ModelError::NotFinite {
            field,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
