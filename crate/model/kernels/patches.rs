//! im2col: a convolution's patches gathered tile by tile, each tile multiplied by a pass's
//! kernel and its rows written to their output pixels.
use super::feature_map::Activation;
use super::matmul::{matmul, workers, zeroed_chunks, Product};
use super::plan::Pass;

/// Floats of patches gathered per tile: keeps a tile (and its product) in the L2 cache.
const TILE_FLOATS: usize = 1 << 17;

/// Pixels per tile for patch rows `row_len` floats long.
pub(super) fn tile_rows(row_len: usize) -> usize {
    (TILE_FLOATS / row_len).clamp(16, 1024)
}

/// Where a convolution reads: grid pixel (i, j) of frame f (grid `[K, H, W]`, pixels counted
/// row-major across frames) reads the input at (scale·i + dy, scale·j + dx) for each tap.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    pub(super) size: [usize; 2],
    pub(super) scale: usize,
}

/// Fills the rows of `col` with the patches (the `[K, H, W, C]` input at `taps` around each
/// grid pixel, zero outside the frame) of the `rows` grid pixels from pixel index `first`.
#[inline(never)]
pub(super) fn gather_patches(
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

/// Where the product rows of a tile go: row r is grid pixel `start + r` of a chunk of grid
/// rows `width` pixels wide, and grid pixel (i, j) writes output pixel
/// (stride·i + phase.0, stride·j + phase.1) of output rows `out_width` pixels wide.
#[derive(Clone, Copy, Debug)]
struct Placement {
    start: usize,
    width: usize,
    stride: usize,
    phase: (usize, usize),
    out_width: usize,
}

/// Writes the product rows of a tile, plus `bias` and `activation`, to their output pixels in
/// `out` (see [`Placement`]).
#[inline(never)]
fn write_rows(
    out: &mut [f32],
    product: &[f32],
    bias: &[f32],
    at: Placement,
    activation: Activation,
) {
    let c_out = bias.len();
    for (r, src) in product.chunks_exact(c_out).enumerate() {
        let (row, j) = ((at.start + r) / at.width, (at.start + r) % at.width);
        let (y, x) = (at.stride * row + at.phase.0, at.stride * j + at.phase.1);
        let dst = &mut out[(y * at.out_width + x) * c_out..][..c_out];
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

/// The passes of a convolution over `grid` of the `[K, H, W, C]` `input`: each pass writes
/// output pixel (stride·i + phase) of grid pixel (i, j), `[K, stride·H_grid, stride·W_grid,
/// C_out]` in all, plus `bias` and `activation`.
pub(super) fn convolve(
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
                let tile = tile_rows(row_len);
                col.resize(tile * row_len, 0.0);
                product.resize(tile * c_out, 0.0);
                for start in (0..pixels).step_by(tile) {
                    let rows = tile.min(pixels - start);
                    let first = first_pixel + start;
                    gather_patches(&mut col, input, shape, grid, &pass.taps, first, rows);
                    let size = [rows, row_len, c_out];
                    matmul(&mut product, &col, &pass.kernel, size, Product::default());
                    let at = Placement {
                        start,
                        width: w,
                        stride,
                        phase: pass.phase,
                        out_width: ow,
                    };
                    write_rows(out, &product[..rows * c_out], bias, at, activation);
                }
            }
        },
    )
}
