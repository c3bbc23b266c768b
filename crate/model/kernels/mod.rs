//! Channels-last feature maps and the inference kernels of the image networks.
//!
//! burn flex's `conv2d` multiplies one frame at a time, so near the 2×2 bottleneck it runs
//! products 4-64 columns wide that re-read megabytes of weights for every frame, and the
//! decoder spends as long again in strided copies (upsampling, layout changes). Here each
//! 3×3 'same' convolution gathers the patches of all frames into small cache-sized tiles
//! (im2col) and multiplies each tile by the kernel with `gemm` (the library flex itself
//! uses). A convolution of a nearest-upsampled map reads the low-resolution map directly and
//! uses the four 2×2 kernels the upsampling collapses the 3×3 kernel into, one per output
//! phase: 4 taps instead of 9, the same sums. Training runs the same kernels through
//! `conv_op` (burn autodiff operations), with their gradients here: the same patches and
//! products, transposed. Tests hold both paths equal to burn's own layers, values and
//! gradients.
mod cache;
mod feature_map;
#[cfg(not(target_arch = "wasm32"))]
mod gradient;
mod heads;
mod matmul;
mod patches;
mod plan;
mod pool;

pub(crate) use cache::KernelCache;
pub(crate) use feature_map::{Activation, FeatureMap};
pub(crate) use heads::{heads, StartValues};
#[cfg(not(target_arch = "wasm32"))]
pub(crate) use plan::Kernels;
#[cfg(not(target_arch = "wasm32"))]
pub(crate) use pool::{max_pool2_gradient, max_pool2_indexed};
