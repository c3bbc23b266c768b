//! Comparisons shared by the model's unit tests.
use burn::tensor::Tensor;

/// The largest absolute difference between two tensors of the same shape.
pub fn max_abs_diff<const D: usize>(a: Tensor<D>, b: Tensor<D>) -> f32 {
    assert_eq!(a.dims(), b.dims());
    (a - b).abs().max().into_scalar()
}

/// Asserts that a gradient equals the expected one within 1e-4 of `scale` (at least 1e-4).
/// Gradients exist natively only (wasm has no autodiff), as do the tests that compare them.
#[cfg(not(target_arch = "wasm32"))]
pub fn assert_gradient_close<const D: usize>(got: Tensor<D>, want: Tensor<D>, scale: f32) {
    let d = max_abs_diff(got, want);
    assert!(d <= 1e-4 * scale.max(1.0), "{d} vs {scale}");
}

/// The largest absolute value of a tensor: the scale of a gradient.
#[cfg(not(target_arch = "wasm32"))]
pub fn max_abs<const D: usize>(t: Tensor<D>) -> f32 {
    t.abs().max().into_scalar()
}
