use burn::tensor::Tensor;

/// A tensor's values, flat, as `f32` (empty if its data cannot be read as `f32`, which flex
/// tensors of floats always can): the one way the crate reads a tensor back.
pub fn values<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .unwrap_or_default()
}
