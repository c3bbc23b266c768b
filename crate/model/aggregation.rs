//! The set operator and the modality blending (the paper's Figure 1, iii).
use burn::tensor::Tensor;

/// Mean over each sequence's real contexts: `[B, N, H]` encodings and a `[B, N]` 0/1 mask to
/// `[B, H]`. Padding slots (mask 0) do not count; a sequence without any context (excluded
/// by [`tensors`](super::tensors)) would give 0.
pub fn masked_mean(encodings: Tensor<3>, mask: Tensor<2>) -> Tensor<2> {
    let mask = mask.unsqueeze_dim::<3>(2);
    let count = mask.clone().sum_dim(1).clamp_min(1.0);
    let sum = (encodings * mask).sum_dim(1);
    (sum / count).squeeze_dim::<2>(1)
}

/// r = c·r_image + (1 − c)·r_joint, with `[B, H]` representations and a `[B]` coefficient.
pub fn blend(image: Tensor<2>, joint: Tensor<2>, c: Tensor<1>) -> Tensor<2> {
    let c = c.unsqueeze_dim::<2>(1);
    image * c.clone() + joint * c.neg().add_scalar(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Device;

    #[test]
    fn padding_is_excluded_from_the_mean() {
        let device = Device::flex();
        let z = Tensor::<3>::from_floats([[[1.0, 2.0], [3.0, 4.0], [100.0, 100.0]]], &device);
        let mask = Tensor::<2>::from_floats([[1.0, 1.0, 0.0]], &device);
        let r: Vec<f32> = masked_mean(z, mask).into_data().try_to_vec().unwrap();
        assert_eq!(r, [2.0, 3.0]);
    }

    #[test]
    fn blend_weights_image_by_c() {
        let device = Device::flex();
        let image = Tensor::<2>::from_floats([[1.0, 1.0], [1.0, 1.0]], &device);
        let joint = Tensor::<2>::from_floats([[3.0, 5.0], [3.0, 5.0]], &device);
        let c = Tensor::<1>::from_floats([0.25, 1.0], &device);
        let r: Vec<f32> = blend(image, joint, c).into_data().try_to_vec().unwrap();
        assert_eq!(r, [2.5, 4.0, 1.0, 1.0]);
    }
}
