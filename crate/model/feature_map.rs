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
use burn::nn::conv::Conv2d;
use burn::tensor::{Device, Tensor, TensorData};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// Floats of patches gathered per tile: keeps a tile (and its product) in the L2 cache.
const TILE_FLOATS: usize = 1 << 17;

/// Pixels per part of a weight gradient's sum (see [`Kernels::weight_gradients`]).
#[cfg(not(target_arch = "wasm32"))]
const PART_PIXELS: usize = 1024;

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
    /// Per tap, the 3×3 kernel cells (ky·3 + kx) summed into it: how its gradient reaches the
    /// weights (training only: not read in wasm).
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    cells: Vec<Vec<usize>>,
}

/// Convolutions prepared for [`FeatureMap::conv3x3`]: their passes and biases, with the
/// weights they were prepared from, so that a cache can tell whether they still hold.
#[derive(Debug)]
pub struct Kernels {
    weights: Vec<Vec<f32>>,
    bias: Vec<f32>,
    c_in: usize,
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

    pub(super) fn prepare(
        weights: Vec<Vec<f32>>,
        bias: Vec<f32>,
        c_in: usize,
        upsampled: bool,
    ) -> Self {
        let c_outs: Vec<usize> = weights.iter().map(|w| w.len() / (9 * c_in)).collect();
        let passes = passes(&weights, &c_outs, c_in, upsampled);
        Kernels {
            weights,
            bias,
            c_in,
            upsampled,
            passes,
        }
    }

    /// These convolutions (see [`FeatureMap::conv3x3`]) of the `[K, H, W, C]` map `input`.
    pub fn apply(&self, input: &[f32], shape: [usize; 4], activation: Activation) -> FeatureMap {
        debug_assert_eq!(shape[3], self.c_in);
        let [k, h, w, _] = shape;
        let grid = Grid {
            size: [h, w],
            scale: 1,
        };
        let stride = self.stride();
        let data = convolve(
            input,
            shape,
            grid,
            &self.passes,
            stride,
            &self.bias,
            activation,
        );
        FeatureMap {
            data,
            shape: [k, stride * h, stride * w, self.bias.len()],
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
/// is costly next to a decode, so they are prepared once and reused while the weights
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
    /// reused without comparing the weights (a cost comparable to a one-target prediction's
    /// own).
    ///
    /// Kernels prepared before are dropped: they may come from earlier weights.
    pub fn freeze(&self) {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        slots.clear();
        self.frozen.store(true, Ordering::Relaxed);
    }

    /// Whether [`KernelCache::freeze`] was called.
    pub fn is_frozen(&self) -> bool {
        self.frozen.load(Ordering::Relaxed)
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
    super::init::conv3x3(channels, device)
}

/// Whether `x` takes part in an autodiff graph (it is trained, or computed from what is):
/// such tensors go through the differentiable operations of `conv_op`, everything else
/// straight through the kernels here. Native only: wasm has no autodiff.
#[cfg(not(target_arch = "wasm32"))]
pub fn is_tracked<const D: usize>(x: &Tensor<D>) -> bool {
    x.is_tracked()
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
    // Which weight (and its first column) each output column comes from.
    let mut columns = Vec::with_capacity(c_total);
    for (weight, &c_out) in weights.iter().zip(c_outs) {
        columns.extend((0..c_out).map(|o| (weight, o)));
    }
    // One kernel row (tap, input channel) per task: training prepares the kernels at every
    // step.
    let kernels: Vec<Vec<f32>> = layouts
        .iter()
        .map(|(_, taps)| {
            let mut kernel = vec![0.0; taps.len() * c_in * c_total];
            for_each_chunk(&mut kernel, c_total.max(1), |row, kernel_row| {
                let (cells, i) = (&taps[row / c_in].1, row % c_in);
                for (k, &(weight, o)) in kernel_row.iter_mut().zip(&columns) {
                    let w = &weight[(o * c_in + i) * 9..][..9];
                    *k = cells.iter().map(|&cell| w[cell]).sum();
                }
            });
            kernel
        })
        .collect();
    layouts
        .into_iter()
        .zip(kernels)
        .map(|((phase, taps), kernel)| {
            let (taps, cells) = taps.into_iter().unzip();
            Pass {
                taps,
                kernel,
                phase,
                cells,
            }
        })
        .collect()
}

/// Where a convolution reads: grid pixel (i, j) of frame f (grid `[K, H, W]`, pixels counted
/// row-major across frames) reads the input at (scale·i + dy, scale·j + dx) for each tap.
#[derive(Clone, Copy, Debug)]
struct Grid {
    size: [usize; 2],
    scale: usize,
}

/// Fills the rows of `col` with the patches (the `[K, H, W, C]` input at `taps` around each
/// grid pixel, zero outside the frame) of the `rows` grid pixels from pixel index `first`.
#[inline(never)]
fn gather_patches(
    col: &mut [f32],
    input: &[f32],
    [_, h, w, c]: [usize; 4],
    Grid {
        size: [gh, gw],
        scale,
    }: Grid,
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
    // A run of pixels in one grid row at a time: each segment's row is checked once per run.
    let mut r = 0;
    while r < rows {
        let p = first + r;
        let (f, i, j0) = (p / (gh * gw), p / gw % gh, p % gw);
        let run = (gw - j0).min(rows - r);
        for &(t, dy, dx, n) in &segments {
            let y = (scale * i) as isize + dy;
            let row_inside = (0..h as isize).contains(&y);
            let base = (f * h + y.clamp(0, h as isize - 1) as usize) * w;
            for jj in 0..run {
                let x = (scale * (j0 + jj)) as isize + dx;
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

/// `out = lhs · rhs` (or `out += lhs · rhs` with `accumulate`) for row-major `rhs` `[k, n]` and
/// `out` `[m, n]`, and `lhs` `[m, k]` row-major or, with `lhs_transposed`, stored as `[k, m]`;
/// split over the workers with `parallel` (natively).
fn matmul(
    out: &mut [f32],
    lhs: &[f32],
    rhs: &[f32],
    [m, k, n]: [usize; 3],
    (lhs_transposed, accumulate, parallel): (bool, bool, bool),
) {
    #[cfg(not(target_arch = "wasm32"))]
    let parallelism = if parallel {
        gemm::Parallelism::Rayon(workers())
    } else {
        gemm::Parallelism::None
    };
    #[cfg(target_arch = "wasm32")]
    let parallelism = {
        let _ = parallel;
        gemm::Parallelism::None
    };
    assert!(out.len() >= m * n && lhs.len() >= m * k && rhs.len() >= k * n);
    let (lhs_cs, lhs_rs) = if lhs_transposed {
        (m as isize, 1)
    } else {
        (1, k as isize)
    };
    // SAFETY: the bounds above cover every element gemm reads or writes with these strides.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            out.as_mut_ptr(),
            1,
            n as isize,
            accumulate,
            lhs.as_ptr(),
            lhs_cs,
            lhs_rs,
            rhs.as_ptr(),
            1,
            n as isize,
            if accumulate { 1.0 } else { 0.0 },
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

/// Runs `f(index, chunk)` over `chunk`-sized pieces of `out`, in parallel natively (wasm has
/// no threads).
fn for_each_chunk<T: Send>(out: &mut [T], chunk: usize, f: impl Fn(usize, &mut [T]) + Send + Sync) {
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

/// A `len`-long vector filled by `f(index, chunk)` over `chunk`-sized pieces (as
/// [`for_each_chunk`]), each piece zeroed first by the worker that fills it, not all of it
/// up front on one thread.
fn zeroed_chunks(
    len: usize,
    chunk: usize,
    f: impl Fn(usize, &mut [f32]) + Send + Sync,
) -> Vec<f32> {
    let mut out: Vec<f32> = Vec::with_capacity(len);
    for_each_chunk(
        &mut out.spare_capacity_mut()[..len],
        chunk.max(1),
        |i, piece| {
            piece.iter_mut().for_each(|x| {
                x.write(0.0);
            });
            // SAFETY: every element of the piece was just initialised, and MaybeUninit<f32> has
            // the layout of f32.
            let piece = unsafe {
                std::slice::from_raw_parts_mut(piece.as_mut_ptr().cast::<f32>(), piece.len())
            };
            f(i, piece)
        },
    );
    // SAFETY: the pieces cover the first `len` elements, each initialised above.
    unsafe { out.set_len(len) };
    out
}

fn workers() -> usize {
    #[cfg(not(target_arch = "wasm32"))]
    return rayon::current_num_threads();
    #[cfg(target_arch = "wasm32")]
    1
}

/// The gradients of a convolution, for training (see `conv_op`): the same patches and products
/// as the forward pass, transposed.
#[cfg(not(target_arch = "wasm32"))]
impl Kernels {
    /// Output channels.
    pub fn c_out(&self) -> usize {
        self.bias.len()
    }

    /// The gradient w.r.t. the `[K, H, W, C_in]` input from `grad`, the gradient w.r.t. the
    /// output before the activation (`[K, s·H, s·W, C_out]`, s = 2 when upsampled): a
    /// convolution of `grad` with the transposed kernels at the mirrored offsets.
    pub fn input_gradient(&self, grad: &[f32], grad_shape: [usize; 4]) -> Vec<f32> {
        let s = self.stride();
        let grid = Grid {
            size: [grad_shape[1] / s, grad_shape[2] / s],
            scale: s,
        };
        let pass = self.input_gradient_pass();
        let zeros = vec![0.0; self.c_in];
        convolve(
            grad,
            grad_shape,
            grid,
            &[pass],
            1,
            &zeros,
            Activation::Identity,
        )
    }

    /// Output pixel (s·i + phase) read input pixel (i + tap) through the block of (phase, tap),
    /// so input pixel (a, b) receives from output pixel (s·a + phase − s·tap) through its
    /// transpose: one pass of taps at those offsets (distinct: 9 plain, 16 upsampled), in
    /// row-major order so that neighbouring taps are copied together.
    fn input_gradient_pass(&self) -> Pass {
        let (s, c_in, c_out) = (self.stride() as isize, self.c_in, self.c_out());
        let mut blocks: Vec<((isize, isize), Vec<f32>)> = Vec::new();
        for pass in &self.passes {
            let phase = (pass.phase.0 as isize, pass.phase.1 as isize);
            for (t, &(dy, dx)) in pass.taps.iter().enumerate() {
                let mut block = vec![0.0; c_out * c_in];
                for i in 0..c_in {
                    let row = &pass.kernel[(t * c_in + i) * c_out..][..c_out];
                    for (o, &v) in row.iter().enumerate() {
                        block[o * c_in + i] = v;
                    }
                }
                blocks.push(((phase.0 - s * dy, phase.1 - s * dx), block));
            }
        }
        blocks.sort_by_key(|(offset, _)| *offset);
        Pass {
            taps: blocks.iter().map(|(offset, _)| *offset).collect(),
            kernel: blocks.into_iter().flat_map(|(_, block)| block).collect(),
            phase: (0, 0),
            cells: Vec::new(),
        }
    }

    /// The gradients w.r.t. the weights (`[C_out, C_in, 3, 3]`, flat) and the bias from the
    /// `[K, H, W, C_in]` input and `grad` (as for [`Kernels::input_gradient`]): per pass, its
    /// patches transposed times the gradient of the pixels it wrote, summed over the tiles of
    /// each worker, then over workers, then onto the kernel cells each tap summed.
    pub fn weight_gradients(
        &self,
        input: &[f32],
        shape: [usize; 4],
        grad: &[f32],
        grad_shape: [usize; 4],
    ) -> (Vec<f32>, Vec<f32>) {
        use rayon::prelude::*;
        let ([k, h, w, c_in], c_out, s) = (shape, self.c_out(), self.stride());
        let pixels = k * h * w;
        // Parts of a fixed size, summed in order: the gradients do not depend on the number of
        // threads or on how rayon splits the work (a resumed training repeats the same losses).
        // With fewer parts than workers, each product is split over the workers instead.
        let per_part = PART_PIXELS;
        let parallel = pixels.div_ceil(per_part) < workers();
        // Per part: per pass, patchesᵀ · gradient; and the gradient's sum over its pixels (each
        // pixel is written by one pass: the bias gradient).
        let parts: Vec<(Vec<Vec<f32>>, Vec<f32>)> = (0..pixels.div_ceil(per_part))
            .into_par_iter()
            .map(|part| {
                let (from, to) = (part * per_part, ((part + 1) * per_part).min(pixels));
                let (mut col, mut g) = (Vec::new(), Vec::new());
                let mut bias = vec![0.0; c_out];
                let grid = |scale| Grid {
                    size: [h, w],
                    scale,
                };
                let sums = self
                    .passes
                    .iter()
                    .map(|pass| {
                        let row_len = pass.taps.len() * c_in;
                        let tile = (TILE_FLOATS / row_len).clamp(16, 1024);
                        col.resize(tile * row_len, 0.0);
                        g.resize(tile * c_out, 0.0);
                        let written = [(pass.phase.0 as isize, pass.phase.1 as isize)];
                        let mut sum = vec![0.0; row_len * c_out];
                        for start in (from..to).step_by(tile) {
                            let rows = tile.min(to - start);
                            let taps = &pass.taps;
                            gather_patches(&mut col, input, shape, grid(1), taps, start, rows);
                            gather_patches(
                                &mut g,
                                grad,
                                grad_shape,
                                grid(s),
                                &written,
                                start,
                                rows,
                            );
                            let size = [row_len, rows, c_out];
                            matmul(&mut sum, &col, &g, size, (true, true, parallel));
                            for px in g[..rows * c_out].chunks_exact(c_out) {
                                bias.iter_mut().zip(px).for_each(|(b, &v)| *b += v);
                            }
                        }
                        sum
                    })
                    .collect::<Vec<_>>();
                (sums, bias)
            })
            .collect();
        let mut parts = parts.into_iter();
        let (sums, bias) = parts
            .next()
            .map(|first| {
                parts.fold(first, |(mut sums, mut bias), (other, other_bias)| {
                    for (sum, other) in sums.iter_mut().zip(&other) {
                        sum.iter_mut().zip(other).for_each(|(a, &b)| *a += b);
                    }
                    bias.iter_mut().zip(&other_bias).for_each(|(a, &b)| *a += b);
                    (sums, bias)
                })
            })
            .unwrap_or_else(|| {
                // No pixels at all.
                let sums = self
                    .passes
                    .iter()
                    .map(|p| vec![0.0; p.taps.len() * c_in * c_out]);
                (sums.collect(), vec![0.0; c_out])
            });
        // Onto the kernel cells each tap summed, one output channel per task.
        let mut weight = vec![0.0; c_out * c_in * 9];
        weight
            .par_chunks_mut(c_in * 9)
            .enumerate()
            .for_each(|(o, weight)| {
                for (pass, sum) in self.passes.iter().zip(&sums) {
                    for (t, cells) in pass.cells.iter().enumerate() {
                        for i in 0..c_in {
                            let v = sum[(t * c_in + i) * c_out + o];
                            for &cell in cells {
                                weight[i * 9 + cell] += v;
                            }
                        }
                    }
                }
            });
        (weight, bias)
    }
}

/// The passes of a convolution over `grid` of the `[K, H, W, C]` `input`: each pass writes
/// output pixel (stride·i + phase) of grid pixel (i, j), `[K, stride·H_grid, stride·W_grid,
/// C_out]` in all, plus `bias` and `activation`.
fn convolve(
    input: &[f32],
    shape: [usize; 4],
    grid: Grid,
    passes: &[Pass],
    stride: usize,
    bias: &[f32],
    activation: Activation,
) -> Vec<f32> {
    let (k, [h, w], c, c_out) = (shape[0], grid.size, shape[3], bias.len());
    let ow = stride * w;
    // Each worker takes a run of grid rows (across frames), which writes a contiguous run of
    // output rows.
    let rows_per_chunk = (k * h).div_ceil(workers()).max(1);
    zeroed_chunks(
        k * stride * h * ow * c_out,
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
                    gather_patches(&mut col, input, shape, grid, &pass.taps, first, rows);
                    matmul(
                        &mut product,
                        &col,
                        &pass.kernel,
                        [rows, row_len, c_out],
                        (false, false, false),
                    );
                    let at = (start, w, stride, pass.phase);
                    write_rows(out, &product[..rows * c_out], bias, at, ow, activation);
                }
            }
        },
    )
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
        kernels.apply(&self.data, self.shape, activation)
    }

    /// 2×2 max pooling with stride 2.
    pub fn max_pool2(&self) -> Self {
        max_pool2_indexed(&self.data, self.shape).0
    }
}

/// 2×2 max pooling with stride 2 of the `[K, H, W, C]` map `input`, and for each output value
/// which of its four inputs (row-major, the first of equals) it came from: where its gradient
/// goes.
pub fn max_pool2_indexed(input: &[f32], [k, h, w, c]: [usize; 4]) -> (FeatureMap, Vec<u8>) {
    let (oh, ow) = (h / 2, w / 2);
    let mut out = vec![0.0; k * oh * ow * c];
    let mut from = vec![0u8; out.len()];
    // One output row per task.
    let pool_row = |row: usize, (out, from): (&mut [f32], &mut [u8])| {
        let (f, i) = (row / oh, row % oh);
        for (j, (dst, idx)) in out
            .chunks_exact_mut(c)
            .zip(from.chunks_exact_mut(c))
            .enumerate()
        {
            let at = |y: usize, x: usize| &input[((f * h + y) * w + x) * c..][..c];
            let quad = [
                at(2 * i, 2 * j),
                at(2 * i, 2 * j + 1),
                at(2 * i + 1, 2 * j),
                at(2 * i + 1, 2 * j + 1),
            ];
            for ch in 0..c {
                let (mut best, mut which) = (quad[0][ch], 0);
                for (q, v) in quad.iter().enumerate().skip(1) {
                    if v[ch] > best {
                        (best, which) = (v[ch], q as u8);
                    }
                }
                dst[ch] = best;
                idx[ch] = which;
            }
        }
    };
    let row = (ow * c).max(1);
    #[cfg(not(target_arch = "wasm32"))]
    {
        use rayon::prelude::*;
        let rows = out.par_chunks_mut(row).zip(from.par_chunks_mut(row));
        rows.enumerate().for_each(|(r, chunks)| pool_row(r, chunks));
    }
    #[cfg(target_arch = "wasm32")]
    {
        let rows = out.chunks_mut(row).zip(from.chunks_mut(row));
        rows.enumerate().for_each(|(r, chunks)| pool_row(r, chunks));
    }
    let map = FeatureMap {
        data: out,
        shape: [k, oh, ow, c],
    };
    (map, from)
}

/// The gradient w.r.t. the `[K, H, W, C]` input of [`max_pool2_indexed`] from the
/// gradient `grad` w.r.t. its output and the `from` indices it returned.
#[cfg(not(target_arch = "wasm32"))]
pub fn max_pool2_gradient(grad: &[f32], from: &[u8], [k, h, w, c]: [usize; 4]) -> Vec<f32> {
    use rayon::prelude::*;
    let ow = w / 2;
    let mut input = vec![0.0; k * h * w * c];
    // Each output row spreads onto two input rows: one pair per task.
    input
        .par_chunks_mut((2 * w * c).max(1))
        .enumerate()
        .for_each(|(row, input)| {
            let at = row * ow * c;
            let (grad, from) = (&grad[at..at + ow * c], &from[at..at + ow * c]);
            for (j, (g, idx)) in grad.chunks_exact(c).zip(from.chunks_exact(c)).enumerate() {
                for ch in 0..c {
                    let q = idx[ch] as usize;
                    input[((q / 2) * w + 2 * j + q % 2) * c + ch] = g[ch];
                }
            }
        });
    input
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::testing::max_abs_diff;
    use crate::model::upsample2;
    use burn::nn::pool::MaxPool2dConfig;
    use burn::tensor::Distribution;

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
    #[cfg(not(target_arch = "wasm32"))]
    fn weight_gradients_do_not_depend_on_the_number_of_threads() {
        let device = Device::flex();
        device.seed(6);
        let conv = new_conv3x3([5, 7], &device);
        let x = Tensor::<4>::random([9, 5, 24, 24], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x);
        let grad = Tensor::<4>::random([9, 48, 48, 7], Distribution::Default, &device);
        let grad = values(grad);
        let kernels = Kernels::new(&[&conv], 5, true);
        let gradients = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let (w, b) = kernels.weight_gradients(&map.data, map.shape, &grad, [9, 48, 48, 7]);
                (w, b, kernels.input_gradient(&grad, [9, 48, 48, 7]))
            })
        };
        // Bit for bit: a resumed training must repeat the same losses.
        assert_eq!(gradients(1), gradients(3));
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
