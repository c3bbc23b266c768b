//! The image decoder's heads at inference, in one pass over their raw outputs: the mean's
//! sigmoid, σ's bounded softplus and the gate's mix with the start frame. burn's element-wise
//! operations take a pass and an allocation each and, in wasm, call libm's scalar `expf` and
//! `log1pf` for every value (a tenth of a frame's decoding once the decoder is small); the
//! exponential and logarithm here are branch-free polynomials that the compiler vectorises,
//! within a few ulp of libm's.

/// A gated decoder's start, per target: its frames `[K, 3, S, S]`, 1 where they are observed
/// (else 0) and their nearness to an observation (see [`crate::model::FrameStart`]).
#[derive(Debug)]
pub(crate) struct StartValues {
    pub(crate) frames: Vec<f32>,
    pub(crate) observed: Vec<f32>,
    pub(crate) near: Vec<f32>,
}

/// What [`heads`] returns, channels-first `[K, 3, S, S]` each.
#[derive(Debug)]
pub(crate) struct HeadValues {
    pub(crate) mean: Vec<f32>,
    pub(crate) sigma: Vec<f32>,
    /// With a gate and a start: the mean before the gate mixed it with the start.
    pub(crate) drawn: Option<Vec<f32>>,
}

/// The mean and σ frames from the heads' channels-last raw outputs `raw` (`[K, S, S, C]`:
/// mean 3, σ 3, then a gate's 1): mean = sigmoid, σ = floor + (1 − floor)·softplus and, with
/// a gate and a start, the mean mixed with the start as [`crate::model::ImageDecoder`] does:
/// g·start + (1 − g)·mean.
pub(crate) fn heads(
    raw: &[f32],
    [k, h, w, c]: [usize; 4],
    floor: f32,
    start: Option<&StartValues>,
) -> HeadValues {
    let hw = h * w;
    let mut mean = vec![0.0; k * 3 * hw];
    let mut sigma = vec![0.0; k * 3 * hw];
    let mut gate = vec![0.0; if c > 6 { hw } else { 0 }];
    let start = start.filter(|_| !gate.is_empty());
    let mut drawn = start.map(|_| vec![0.0; k * 3 * hw]);
    for f in 0..k {
        let m = &mut mean[f * 3 * hw..][..3 * hw];
        let s = &mut sigma[f * 3 * hw..][..3 * hw];
        for (p, v) in raw[f * hw * c..][..hw * c].chunks_exact(c).enumerate() {
            for ch in 0..3 {
                m[ch * hw + p] = v[ch];
                s[ch * hw + p] = v[3 + ch];
            }
            if let Some(g) = gate.get_mut(p) {
                *g = v[6];
            }
        }
        m.iter_mut().for_each(|x| *x = sigmoid(*x));
        s.iter_mut()
            .for_each(|x| *x = floor + (1.0 - floor) * softplus(*x));
        let (Some(start), Some(drawn)) = (start, &mut drawn) else {
            continue;
        };
        drawn[f * 3 * hw..][..3 * hw].copy_from_slice(m);
        let (observed, near) = (start.observed[f], start.near[f]);
        gate.iter_mut()
            .for_each(|g| *g = (sigmoid(*g) * (1.0 - near) + near) * observed);
        let frames = &start.frames[f * 3 * hw..][..3 * hw];
        for (m, frames) in m.chunks_exact_mut(hw).zip(frames.chunks_exact(hw)) {
            for ((m, &x), &g) in m.iter_mut().zip(frames).zip(&gate) {
                *m = x * g + *m * (1.0 - g);
            }
        }
    }
    HeadValues { mean, sigma, drawn }
}

/// 1 / (1 + e^−x).
#[inline(always)]
fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + exp(-x))
}

/// ln(1 + e^x), as max(x, 0) + ln(1 + e^−|x|) (no overflow).
#[inline(always)]
fn softplus(x: f32) -> f32 {
    // A comparison, not f32::max: wasm would call libm's fmaxf.
    let positive = if x > 0.0 { x } else { 0.0 };
    positive + ln_1p_unit(exp(-x.abs()))
}

/// e^x (Cephes' `expf`): x = n·ln 2 + r with |r| ≤ ln 2 / 2, e^r by a degree-6 polynomial,
/// 2^n from the exponent bits. Inputs are clamped to [−87, 88], where e^x is a normal float.
#[inline(always)]
fn exp(x: f32) -> f32 {
    let x = x.clamp(-87.0, 88.0);
    let n = (x * std::f32::consts::LOG2_E).round_ties_even();
    // ln 2 in two parts, so that n·ln 2 is exact enough.
    let r = x - n * 0.693_359_4 + n * 2.121_944_4e-4;
    let mut p = 1.987_569_2e-4_f32;
    for c in [1.398_2e-3, 8.333_452e-3, 4.166_579_6e-2, 0.166_666_65, 0.5] {
        p = p * r + c;
    }
    let y = p * r * r + r + 1.0;
    y * f32::from_bits(((n as i32 + 127) << 23) as u32)
}

/// ln(1 + y) for y in [0, 1]: 2·atanh(s) with s = y / (2 + y) ≤ 1/3, by its series to s^13
/// (the next term is below 1e-8).
#[inline(always)]
fn ln_1p_unit(y: f32) -> f32 {
    let s = y / (2.0 + y);
    let t = s * s;
    let mut p = 1.0 / 13.0_f32;
    for c in [1.0 / 11.0, 1.0 / 9.0, 1.0 / 7.0, 1.0 / 5.0, 1.0 / 3.0, 1.0] {
        p = p * t + c;
    }
    2.0 * s * p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_and_ln_1p_are_within_a_few_ulp_of_libm() {
        let mut worst = [0.0_f64; 3];
        for i in -200_000..=200_000 {
            let x = i as f32 * 4.0e-4; // [-80, 80]
            let want = (x as f64).exp();
            worst[0] = worst[0].max(((exp(x) as f64 - want) / want).abs());
            let want = (x as f64).exp().ln_1p();
            worst[1] = worst[1].max(((softplus(x) as f64 - want) / want).abs());
            let want = 1.0 / (1.0 + (-x as f64).exp());
            worst[2] = worst[2].max(((sigmoid(x) as f64 - want) / want).abs());
        }
        // f32's epsilon is 1.2e-7.
        assert!(worst.iter().all(|&e| e < 5e-7), "relative errors {worst:?}");
        // Far out: finite, and the limits.
        assert!((0.0..1e-37).contains(&sigmoid(-1e4)));
        assert_eq!(sigmoid(1e4), 1.0);
        assert_eq!(softplus(1e4), 1e4);
        assert!(exp(-1e4) > 0.0 && exp(1e4).is_finite());
    }
}
