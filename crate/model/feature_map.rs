//! Channels-last feature maps and the inference kernels of the image networks.
//!
//! burn flex's `conv2d` multiplies one frame at a time, so near the 2×2 bottleneck it runs
//! products 4-64 columns wide that re-read megabytes of weights for every frame, and the
//! decoder spends as long again in strided copies (upsampling, layout changes). Here each
//! 3×3 'same' convolution gathers the patches of all frames into small cache-sized tiles
//! (im2col) and multiplies each tile by the kernel with `gemm` (the library flex itself
//! uses). A convolution of a nearest-upsampled map reads the low-resolution map directly and
//! uses the four 2×2 kernels the upsampling collapses the 3×3 kernel into, one per output
//! phase: 4 taps instead of 9, the same sums. Inference only: training goes through burn's
//! differentiable `conv2d` (see the `forward_differentiable` methods), and tests hold the two
//! paths equal.
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::PaddingConfig2d;
use burn::tensor::{Device, Tensor, TensorData};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// Floats of patches gathered per tile: keeps a tile (and its product) in the L2 cache.
const TILE_FLOATS: usize = 1 << 17;

/// A stack of K feature maps, `[K, H, W, C]` in row-major order (channels last).
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureMap {
    /// The values, `K·H·W·C` of them.
    pub data: Vec<f32>,
    /// `[K, H, W, C]`.
    pub shape: [usize; 4],
}

/// What follows a convolution, applied as its result is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activation {
    /// Nothing.
    Identity,
    /// max(0, x).
    Relu,
}

/// One matrix product of a convolution: the input offsets it reads and its kernel
/// (`[taps·C_in, C_out]`, rows ordered (tap, channel)), writing the output pixels
/// `(stride·i + phase.0, stride·j + phase.1)`.
#[derive(Debug)]
struct Pass {
    taps: Vec<(isize, isize)>,
    kernel: Vec<f32>,
    phase: (usize, usize),
}

/// Convolutions prepared for [`FeatureMap::conv3x3`]: their passes and biases, with the
/// weights they were prepared from, so that a cache can tell whether they still hold.
#[derive(Debug)]
pub struct Kernels {
    weights: Vec<Vec<f32>>,
    bias: Vec<f32>,
    upsampled: bool,
    passes: Vec<Pass>,
}

impl Kernels {
    /// The weights and biases of `convs` over `c_in` input channels, each as flat values.
    fn read(convs: &[&Conv2d], c_in: usize) -> (Vec<Vec<f32>>, Vec<f32>) {
        let mut weights = Vec::new();
        let mut bias = Vec::new();
        for conv in convs {
            let [c_out, c, kh, kw] = conv.weight.dims();
            assert_eq!(
                [c, kh, kw],
                [c_in, 3, 3],
                "a 3x3 kernel over {c_in} channels"
            );
            weights.push(values(conv.weight.val()));
            match &conv.bias {
                Some(b) => bias.extend(values(b.val())),
                None => bias.extend(std::iter::repeat_n(0.0, c_out)),
            }
        }
        (weights, bias)
    }

    /// Prepares `convs` (their outputs side by side) over `c_in` input channels, reading the
    /// input directly or, with `upsampled`, its nearest 2× upsampling.
    pub fn new(convs: &[&Conv2d], c_in: usize, upsampled: bool) -> Self {
        let (weights, bias) = Self::read(convs, c_in);
        Self::prepare(weights, bias, c_in, upsampled)
    }

    fn prepare(weights: Vec<Vec<f32>>, bias: Vec<f32>, c_in: usize, upsampled: bool) -> Self {
        let c_outs: Vec<usize> = weights.iter().map(|w| w.len() / (9 * c_in)).collect();
        let passes = passes(&weights, &c_outs, c_in, upsampled);
        Kernels {
            weights,
            bias,
            upsampled,
            passes,
        }
    }

    /// Output pixels per input pixel along each axis: 2 when the input is read upsampled.
    fn stride(&self) -> usize {
        if self.upsampled {
            2
        } else {
            1
        }
    }
}

/// Prepared convolutions kept by an image network, one slot per layer: preparing the kernels
/// costs about a tenth of a decode, so they are prepared once and reused while the weights
/// they came from stay the same: compared exactly on each use (training or loading other
/// weights prepares them anew) unless the owner has promised, with
/// [`KernelCache::freeze`], that they never change. A copy of the network (a clone, as burn
/// makes for `valid()` or before an update) starts with an empty cache of its own.
#[derive(Debug, Default)]
pub struct KernelCache {
    slots: Mutex<Vec<Option<Arc<Kernels>>>>,
    frozen: AtomicBool,
}

impl Clone for KernelCache {
    fn clone(&self) -> Self {
        KernelCache::default()
    }
}

impl KernelCache {
    /// Promises that the network's weights will not change any more (its owner only ever
    /// reads it, as a [`Predictor`](crate::predict::Predictor) does), so prepared kernels are
    /// reused without comparing the weights: a one-target prediction spends a quarter of its
    /// time on that comparison otherwise.
    ///
    /// Kernels prepared before are dropped: they may come from earlier weights.
    pub fn freeze(&self) {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        slots.clear();
        self.frozen.store(true, Ordering::Relaxed);
    }

    /// The kernels of `convs` in `slot`, prepared now if the slot is empty or holds others.
    pub fn get(
        &self,
        slot: usize,
        convs: &[&Conv2d],
        c_in: usize,
        upsampled: bool,
    ) -> Arc<Kernels> {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        if slots.len() <= slot {
            slots.resize(slot + 1, None);
        }
        if let Some(k) = &slots[slot] {
            if k.upsampled == upsampled && self.frozen.load(Ordering::Relaxed) {
                return k.clone();
            }
        }
        let (weights, bias) = Kernels::read(convs, c_in);
        if let Some(k) = &slots[slot] {
            if k.upsampled == upsampled && k.weights == weights && k.bias == bias {
                return k.clone();
            }
        }
        let kernels = Arc::new(Kernels::prepare(weights, bias, c_in, upsampled));
        slots[slot] = Some(kernels.clone());
        kernels
    }
}

/// The rows of a 3×3 kernel that fall on each low-resolution row when the input was
/// upsampled by 2, for output phase 0 and 1: (row offset, kernel rows summed).
const UPSAMPLED_TAPS: [[(isize, &[usize]); 2]; 2] =
    [[(-1, &[0]), (0, &[1, 2])], [(0, &[0, 1]), (1, &[2])]];

/// A 3×3 'same' convolution from `channels[0]` to `channels[1]` channels: the layer both
/// image networks are built of.
pub fn new_conv3x3(channels: [usize; 2], device: &Device) -> Conv2d {
    Conv2dConfig::new(channels, [3, 3])
        .with_padding(PaddingConfig2d::Same)
        .init(device)
}

/// Whether `x` takes part in an autodiff graph (it is trained, or computed from what is):
/// such tensors go through burn's differentiable layers, everything else through the kernels
/// here. Without autodiff (wasm) nothing is tracked.
pub fn is_tracked<const D: usize>(x: &Tensor<D>) -> bool {
    #[cfg(not(target_arch = "wasm32"))]
    return x.is_tracked();
    #[cfg(target_arch = "wasm32")]
    {
        let _ = x;
        false
    }
}

fn values<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_into_vec::<f32>()
        .expect("f32 data")
}

/// A tap of a pass: the input offset and the kernel cells (ky·3 + kx) summed into it.
type Tap = ((isize, isize), Vec<usize>);

/// The passes of the convolutions `weights` (each `[C_out, C_in, 3, 3]`, C_out in `c_outs`; their
/// outputs side by side), reading the input directly or, with `upsampled`, its nearest 2×
/// upsampling.
#[inline(never)]
fn passes(weights: &[Vec<f32>], c_outs: &[usize], c_in: usize, upsampled: bool) -> Vec<Pass> {
    // Per pass: its phase and its taps.
    let layouts: Vec<((usize, usize), Vec<Tap>)> = if upsampled {
        let mut all = Vec::with_capacity(4);
        for (py, rows) in UPSAMPLED_TAPS.iter().enumerate() {
            for (px, cols) in UPSAMPLED_TAPS.iter().enumerate() {
                let mut taps = Vec::with_capacity(4);
                for &(dy, kys) in rows {
                    for &(dx, kxs) in cols {
                        let cells = kys
                            .iter()
                            .flat_map(|&ky| kxs.iter().map(move |&kx| ky * 3 + kx));
                        taps.push(((dy, dx), cells.collect()));
                    }
                }
                all.push(((py, px), taps));
            }
        }
        all
    } else {
        let taps = (0..9)
            .map(|cell| {
                (
                    ((cell / 3) as isize - 1, (cell % 3) as isize - 1),
                    vec![cell],
                )
            })
            .collect();
        vec![((0, 0), taps)]
    };
    let c_total: usize = c_outs.iter().sum();
    let mut kernels: Vec<Vec<f32>> = layouts
        .iter()
        .map(|(_, taps)| vec![0.0; taps.len() * c_in * c_total])
        .collect();
    let mut column = 0;
    for (weight, c_out) in weights.iter().zip(c_outs) {
        for o in 0..*c_out {
            for i in 0..c_in {
                let w = &weight[(o * c_in + i) * 9..][..9];
                for ((_, taps), kernel) in layouts.iter().zip(&mut kernels) {
                    for (t, (_, cells)) in taps.iter().enumerate() {
                        kernel[(t * c_in + i) * c_total + column + o] =
                            cells.iter().map(|&cell| w[cell]).sum();
                    }
                }
            }
        }
        column += c_out;
    }
    layouts
        .into_iter()
        .zip(kernels)
        .map(|((phase, taps), kernel)| Pass {
            taps: taps.into_iter().map(|(offset, _)| offset).collect(),
            kernel,
            phase,
        })
        .collect()
}

/// Fills the rows of `col` with the patches (the input at `taps` around each pixel, zero
/// outside the frame) of the `rows` pixels from pixel index `first` of the `[K, H, W, C]` map.
#[inline(never)]
fn gather_patches(
    col: &mut [f32],
    input: &[f32],
    [_, h, w, c]: [usize; 4],
    taps: &[(isize, isize)],
    first: usize,
    rows: usize,
) {
    let row_len = taps.len() * c;
    // Taps next to each other in one input row read neighbouring pixels, which lie side by
    // side in both the input and the patch: copy each such segment (first tap, offsets, taps)
    // at once where it lies inside the frame.
    let mut segments: Vec<(usize, isize, isize, usize)> = Vec::with_capacity(taps.len());
    for (t, &(dy, dx)) in taps.iter().enumerate() {
        match segments.last_mut() {
            Some((_, sy, sx, n)) if *sy == dy && *sx + *n as isize == dx => *n += 1,
            _ => segments.push((t, dy, dx, 1)),
        }
    }
    // A run of pixels in one input row at a time: each segment's row is checked once per run.
    let mut r = 0;
    while r < rows {
        let p = first + r;
        let (f, i, j0) = (p / (h * w), p / w % h, p % w);
        let run = (w - j0).min(rows - r);
        for &(t, dy, dx, n) in &segments {
            let y = i as isize + dy;
            let row_inside = (0..h as isize).contains(&y);
            let base = (f * h + y.max(0) as usize) * w;
            for jj in 0..run {
                let x = (j0 + jj) as isize + dx;
                let dst = &mut col[(r + jj) * row_len + t * c..][..n * c];
                if row_inside && x >= 0 && x + n as isize <= w as isize {
                    let at = (base + x as usize) * c;
                    dst.copy_from_slice(&input[at..at + n * c]);
                } else {
                    // At the frame's edge: tap by tap.
                    for (k, d) in dst.chunks_exact_mut(c).enumerate() {
                        let x = x + k as isize;
                        if row_inside && (0..w as isize).contains(&x) {
                            let at = (base + x as usize) * c;
                            d.copy_from_slice(&input[at..at + c]);
                        } else {
                            d.fill(0.0);
                        }
                    }
                }
            }
        }
        r += run;
    }
}

/// Writes the product rows of the pixels from `start` (within a chunk of input rows `w`
/// wide), plus `bias` and `activation`, to their output pixels (`stride`, `phase`) in `out`,
/// whose rows are `ow` pixels wide.
#[inline(never)]
fn write_rows(
    out: &mut [f32],
    product: &[f32],
    bias: &[f32],
    (start, w, stride, phase): (usize, usize, usize, (usize, usize)),
    ow: usize,
    activation: Activation,
) {
    let c_out = bias.len();
    for (r, src) in product.chunks_exact(c_out).enumerate() {
        let (row, j) = ((start + r) / w, (start + r) % w);
        let (y, x) = (stride * row + phase.0, stride * j + phase.1);
        let dst = &mut out[(y * ow + x) * c_out..][..c_out];
        for ((d, &s), &b) in dst.iter_mut().zip(src).zip(bias) {
            *d = s + b;
        }
        if activation == Activation::Relu {
            // A comparison, not f32::max: wasm would call libm's fmaxf.
            dst.iter_mut()
                .for_each(|d| *d = if *d > 0.0 { *d } else { 0.0 });
        }
    }
}

/// `out = lhs · rhs` for row-major `lhs` `[m, k]`, `rhs` `[k, n]`, `out` `[m, n]`.
fn matmul(out: &mut [f32], lhs: &[f32], rhs: &[f32], m: usize, k: usize, n: usize) {
    assert!(out.len() >= m * n && lhs.len() >= m * k && rhs.len() >= k * n);
    // SAFETY: the bounds above cover every element gemm reads or writes with these strides.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            out.as_mut_ptr(),
            1,
            n as isize,
            false,
            lhs.as_ptr(),
            1,
            k as isize,
            rhs.as_ptr(),
            1,
            n as isize,
            0.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        );
    }
}

/// Runs `f(index, chunk)` over `chunk`-sized pieces of `out`, in parallel natively (wasm has
/// no threads).
fn for_each_chunk(out: &mut [f32], chunk: usize, f: impl Fn(usize, &mut [f32]) + Send + Sync) {
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        out.par_chunks_mut(chunk)
            .enumerate()
            .for_each(|(i, c)| f(i, c));
    }
    #[cfg(target_arch = "wasm32")]
    out.chunks_mut(chunk).enumerate().for_each(|(i, c)| f(i, c));
}

fn workers() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    return rayon::current_num_threads();
    #[cfg(target_arch = "wasm32")]
    1
}

impl FeatureMap {
    /// From a channels-first `[K, C, H, W]` tensor.
    pub fn from_channels_first(x: Tensor<4>) -> Self {
        let [k, c, h, w] = x.dims();
        let src = values(x);
        let mut data = vec![0.0; src.len()];
        for f in 0..k {
            for ch in 0..c {
                let plane = &src[(f * c + ch) * h * w..][..h * w];
                for (p, &v) in plane.iter().enumerate() {
                    data[(f * h * w + p) * c + ch] = v;
                }
            }
        }
        FeatureMap {
            data,
            shape: [k, h, w, c],
        }
    }

    /// Channels-first tensors on `device` of consecutive channel groups of `sizes` channels,
    /// each `[K, size, H, W]`.
    pub fn into_channels_first(self, sizes: &[usize], device: &Device) -> Vec<Tensor<4>> {
        let [k, h, w, c] = self.shape;
        debug_assert_eq!(sizes.iter().sum::<usize>(), c);
        let mut first = 0;
        sizes
            .iter()
            .map(|&size| {
                let mut out = vec![0.0; k * size * h * w];
                for f in 0..k {
                    for p in 0..h * w {
                        let src = &self.data[(f * h * w + p) * c + first..][..size];
                        for (ch, &v) in src.iter().enumerate() {
                            out[(f * size + ch) * h * w + p] = v;
                        }
                    }
                }
                first += size;
                Tensor::from_data(TensorData::new(out, [k, size, h, w]), device)
            })
            .collect()
    }

    /// The prepared 3×3 'same' convolutions `kernels` (their outputs side by side as channels)
    /// of this map or, if they were prepared so, of its nearest 2× upsampling, followed by
    /// `activation`.
    pub fn conv3x3(&self, kernels: &Kernels, activation: Activation) -> Self {
        let [k, h, w, c] = self.shape;
        let (passes, stride, bias) = (&kernels.passes, kernels.stride(), &kernels.bias);
        let c_out = bias.len();
        debug_assert_eq!(
            kernels.weights.iter().map(Vec::len).sum::<usize>(),
            9 * c * c_out
        );
        let (oh, ow) = (stride * h, stride * w);
        let mut out = vec![0.0; k * oh * ow * c_out];
        // Each worker takes a run of input rows (across frames), which writes a contiguous run
        // of output rows.
        let rows_per_chunk = (k * h).div_ceil(workers()).max(1);
        let input = &self.data;
        for_each_chunk(
            &mut out,
            rows_per_chunk * stride * ow * c_out,
            |chunk, out| {
                let first_pixel = chunk * rows_per_chunk * w;
                let pixels = out.len() / (stride * ow * c_out) * w;
                let mut col = Vec::new();
                let mut product = Vec::new();
                for pass in passes {
                    let row_len = pass.taps.len() * c;
                    let tile = (TILE_FLOATS / row_len).clamp(16, 1024);
                    col.resize(tile * row_len, 0.0);
                    product.resize(tile * c_out, 0.0);
                    for start in (0..pixels).step_by(tile) {
                        let rows = tile.min(pixels - start);
                        let first = first_pixel + start;
                        gather_patches(&mut col, input, self.shape, &pass.taps, first, rows);
                        matmul(&mut product, &col, &pass.kernel, rows, row_len, c_out);
                        let at = (start, w, stride, pass.phase);
                        write_rows(out, &product[..rows * c_out], bias, at, ow, activation);
                    }
                }
            },
        );
        FeatureMap {
            data: out,
            shape: [k, oh, ow, c_out],
        }
    }

    /// 2×2 max pooling with stride 2.
    pub fn max_pool2(&self) -> Self {
        let [k, h, w, c] = self.shape;
        let (oh, ow) = (h / 2, w / 2);
        let mut out = vec![0.0; k * oh * ow * c];
        for (o, dst) in out.chunks_exact_mut(c).enumerate() {
            let (f, i, j) = (o / (oh * ow), o / ow % oh, o % ow);
            let at = |y: usize, x: usize| &self.data[((f * h + y) * w + x) * c..][..c];
            let (a, b) = (at(2 * i, 2 * j), at(2 * i, 2 * j + 1));
            let (d, e) = (at(2 * i + 1, 2 * j), at(2 * i + 1, 2 * j + 1));
            let max = |x: f32, y: f32| if x > y { x } else { y };
            for ch in 0..c {
                dst[ch] = max(max(a[ch], b[ch]), max(d[ch], e[ch]));
            }
        }
        FeatureMap {
            data: out,
            shape: [k, oh, ow, c],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::upsample2;
    use burn::nn::pool::MaxPool2dConfig;
    use burn::tensor::Distribution;

    fn max_abs_diff(a: Tensor<4>, b: Tensor<4>) -> f32 {
        assert_eq!(a.dims(), b.dims());
        (a - b).abs().max().into_scalar()
    }

    #[test]
    fn conv3x3_equals_burns_conv2d_plain_upsampled_and_stacked() {
        let device = Device::flex();
        device.seed(3);
        for (k, c_in, c_out, s) in [(3, 4, 8, 8), (2, 5, 3, 2), (9, 16, 4, 16)] {
            let a = new_conv3x3([c_in, c_out], &device);
            let b = new_conv3x3([c_in, 2], &device);
            let x = Tensor::<4>::random([k, c_in, s, s], Distribution::Default, &device);
            let map = FeatureMap::from_channels_first(x.clone());
            for upsampled in [false, true] {
                let input = if upsampled {
                    upsample2(x.clone())
                } else {
                    x.clone()
                };
                let kernels = Kernels::new(&[&a, &b], c_in, upsampled);
                let got = map
                    .conv3x3(&kernels, Activation::Relu)
                    .into_channels_first(&[c_out, 2], &device);
                let expected = [a.forward(input.clone()), b.forward(input)];
                for (g, e) in got.into_iter().zip(expected) {
                    let d = max_abs_diff(g, burn::tensor::activation::relu(e));
                    assert!(d < 1e-5, "{k} {c_in} {c_out} {s} {upsampled}: {d}");
                }
            }
        }
    }

    #[test]
    fn the_cache_reuses_kernels_only_while_the_weights_are_the_same() {
        let device = Device::flex();
        device.seed(5);
        let (a, b) = (new_conv3x3([3, 4], &device), new_conv3x3([3, 4], &device));
        let x = Tensor::<4>::random([2, 3, 4, 4], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x.clone());
        let cache = KernelCache::default();
        let first = cache.get(0, &[&a], 3, false);
        assert!(Arc::ptr_eq(&first, &cache.get(0, &[&a], 3, false)));
        // Other weights in the same slot (as after a training step) are prepared anew.
        let other = cache.get(0, &[&b], 3, false);
        assert!(!Arc::ptr_eq(&first, &other));
        let got = map.conv3x3(&other, Activation::Identity);
        let got = got.into_channels_first(&[4], &device).remove(0);
        assert!(max_abs_diff(got, b.forward(x)) < 1e-5);
        let upsampled = cache.get(0, &[&b], 3, true);
        assert!(!Arc::ptr_eq(&other, &upsampled));
        // Frozen, the slot's kernels stand whatever weights are passed (the owner promised no
        // change); a copy of the cache starts empty.
        cache.freeze();
        let frozen = cache.get(0, &[&b], 3, true);
        assert!(!Arc::ptr_eq(&upsampled, &frozen), "freezing starts afresh");
        assert!(Arc::ptr_eq(&frozen, &cache.get(0, &[&a], 3, true)));
        let copy = cache.clone();
        assert!(!Arc::ptr_eq(&frozen, &copy.get(0, &[&b], 3, true)));
        // No frames at all (a prediction of no target times) is an empty map, not a panic.
        let empty = FeatureMap {
            data: Vec::new(),
            shape: [0, 4, 4, 3],
        };
        assert_eq!(empty.conv3x3(&other, Activation::Relu).shape, [0, 4, 4, 4]);
    }

    #[test]
    fn max_pool2_and_layout_round_trip() {
        let device = Device::flex();
        device.seed(4);
        let x = Tensor::<4>::random([2, 3, 4, 6], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x.clone());
        let back = map.clone().into_channels_first(&[3], &device).remove(0);
        assert_eq!(max_abs_diff(back, x.clone()), 0.0);
        let pooled = map.max_pool2().into_channels_first(&[3], &device).remove(0);
        let expected = MaxPool2dConfig::new([2, 2]).init().forward(x);
        assert_eq!(max_abs_diff(pooled, expected), 0.0);
    }
}
