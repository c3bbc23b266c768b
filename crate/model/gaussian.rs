use burn::tensor::activation::softplus;
use burn::tensor::Tensor;

/// The Gaussian heads' scale: `σ = floor + (1 − floor)·softplus(raw)`, so σ > floor and
/// the raw output's zero maps to σ ≈ 0.69 (the Neural Process Family library's form; the
/// original DMBN used a bare softplus for joints and a sigmoid for images).
pub fn bounded_sigma<const D: usize>(raw: Tensor<D>, floor: f64) -> Tensor<D> {
    softplus(raw, 1.0).mul_scalar(1.0 - floor).add_scalar(floor)
}
