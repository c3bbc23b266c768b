//! Independent checks of the goldens, which the code under test blesses. The golden prediction
//! (tests/golden/prediction.json): the shipped DMBN computed here in plain loops from its
//! exported tensors (PyTorch names and layouts, `dmbn export`), following the PyTorch twin
//! (python/dmbn_torch/) rather than the burn sources, with no tensor library. The golden
//! scores (tests/golden/score.json): the scenarios' steps, the trivial baseline and every error
//! and NLL measure recomputed here from the definitions in docs/results.md, for the baseline
//! and for the model's prediction. Runs everywhere (the twin itself needs torch); a few target
//! steps keep the network to about a second. Native only.
#![cfg(not(target_arch = "wasm32"))]

#[path = "golden/prediction.rs"]
mod golden;
#[path = "golden/score.rs"]
mod golden_score;
mod support;

use std::collections::HashMap;

use dmbn::model::export_safetensors;
use dmbn::predict::{Observations, Predictor};
use dmbn::quality::Scenario;
use dmbn::sim::{episode, Action};
use safetensors::SafeTensors;

/// The exported tensors by name: shape and values.
struct Weights(HashMap<String, (Vec<usize>, Vec<f32>)>);

impl Weights {
    fn get(&self, name: &str) -> (&[usize], &[f32]) {
        let (shape, values) = self
            .0
            .get(name)
            .unwrap_or_else(|| panic!("no tensor {name}"));
        (shape, values)
    }

    /// `y = W x + b` of the PyTorch `Linear` `name` (W is [out, in]).
    fn linear(&self, name: &str, x: &[f32]) -> Vec<f32> {
        let (shape, w) = self.get(&format!("{name}.weight"));
        let (_, b) = self.get(&format!("{name}.bias"));
        let (out, inputs) = (shape[0], shape[1]);
        assert_eq!(x.len(), inputs, "{name}: input width");
        (0..out)
            .map(|o| b[o] + (0..inputs).map(|i| w[o * inputs + i] * x[i]).sum::<f32>())
            .collect()
    }

    /// The PyTorch `Conv2d` `name` (3×3, padding 1) on a [C, S, S] image.
    fn conv3x3(&self, name: &str, x: &[f32], size: usize) -> Vec<f32> {
        let (shape, w) = self.get(&format!("{name}.weight"));
        let (_, b) = self.get(&format!("{name}.bias"));
        let (out, inputs) = (shape[0], shape[1]);
        assert_eq!(x.len(), inputs * size * size, "{name}: input channels");
        let mut y = vec![0.0f32; out * size * size];
        for o in 0..out {
            for r in 0..size {
                for c in 0..size {
                    let mut sum = b[o];
                    for i in 0..inputs {
                        for (dr, dc) in (0..3).flat_map(|dr| (0..3).map(move |dc| (dr, dc))) {
                            let (rr, cc) =
                                (r as isize + dr as isize - 1, c as isize + dc as isize - 1);
                            if rr < 0 || cc < 0 || rr >= size as isize || cc >= size as isize {
                                continue;
                            }
                            let pixel = x[(i * size + rr as usize) * size + cc as usize];
                            sum += w[((o * inputs + i) * 3 + dr) * 3 + dc] * pixel;
                        }
                    }
                    y[(o * size + r) * size + c] = sum;
                }
            }
        }
        y
    }
}

fn relu(mut x: Vec<f32>) -> Vec<f32> {
    x.iter_mut().for_each(|v| *v = v.max(0.0));
    x
}

/// 2×2 max pooling of a [C, S, S] image.
fn max_pool(x: &[f32], channels: usize, size: usize) -> Vec<f32> {
    let half = size / 2;
    let mut y = vec![0.0; channels * half * half];
    for ch in 0..channels {
        for r in 0..half {
            for c in 0..half {
                let at = |dr: usize, dc: usize| x[(ch * size + 2 * r + dr) * size + 2 * c + dc];
                y[(ch * half + r) * half + c] = at(0, 0).max(at(0, 1)).max(at(1, 0)).max(at(1, 1));
            }
        }
    }
    y
}

/// Nearest-neighbour ×2 upsampling of a [C, S, S] image.
fn upsample(x: &[f32], channels: usize, size: usize) -> Vec<f32> {
    let double = 2 * size;
    let mut y = vec![0.0; channels * double * double];
    for ch in 0..channels {
        for r in 0..double {
            for c in 0..double {
                y[(ch * double + r) * double + c] = x[(ch * size + r / 2) * size + c / 2];
            }
        }
    }
    y
}

fn sigmoid(v: f32) -> f32 {
    1.0 / (1.0 + (-v).exp())
}

/// σ = floor + (1 − floor)·softplus(raw).
fn bounded_sigma(raw: f32, floor: f32) -> f32 {
    floor + (1.0 - floor) * raw.exp().ln_1p()
}

/// Number of output channels of convolution `name`.
fn channels(w: &Weights, name: &str) -> usize {
    w.get(&format!("{name}.weight")).0[0]
}

/// The image encoder (conv + ReLU + max-pool blocks down to 2×2, dense + ReLU) on [4, S, S].
fn encode_image(w: &Weights, mut x: Vec<f32>, mut size: usize) -> Vec<f32> {
    let mut k = 0;
    while w.0.contains_key(&format!("image_encoder.convs.{k}.weight")) {
        let name = format!("image_encoder.convs.{k}");
        x = max_pool(&relu(w.conv3x3(&name, &x, size)), channels(w, &name), size);
        size /= 2;
        k += 1;
    }
    assert_eq!(size, 2, "the encoder ends at 2×2");
    relu(w.linear("image_encoder.dense", &x))
}

/// A stack of `prefix.{k}` linear layers, each followed by ReLU.
fn mlp(w: &Weights, prefix: &str, mut x: Vec<f32>) -> Vec<f32> {
    let mut k = 0;
    while w.0.contains_key(&format!("{prefix}.{k}.weight")) {
        x = relu(w.linear(&format!("{prefix}.{k}"), &x));
        k += 1;
    }
    x
}

/// The decoder on one [r, t] input: (image mean [S, S, 3], image σ [S, S, 3], joint mean [7],
/// joint σ [7]), all in the network's units (joints normalised).
fn decode(w: &Weights, input: &[f32], floor: f32) -> [Vec<f32>; 4] {
    let shared = relu(w.linear("decoder.shared", input));
    // The image decoder: blocks from 2×2, upsampled before every block but the first and
    // before the first tail convolution (the shipped DMBN's tail is not coarse).
    let (mut y, mut size) = (shared.clone(), 2);
    let names: Vec<String> = (0..)
        .map(|k| format!("decoder.image.blocks.{k}"))
        .take_while(|n| w.0.contains_key(&format!("{n}.weight")))
        .chain(
            (0..)
                .map(|k| format!("decoder.image.tail.{k}"))
                .take_while(|n| w.0.contains_key(&format!("{n}.weight"))),
        )
        .collect();
    let mut ch = 256;
    for (i, name) in names.iter().enumerate() {
        if i > 0 && name.contains("blocks") || name.ends_with("tail.0") {
            y = upsample(&y, ch, size);
            size *= 2;
        }
        y = relu(w.conv3x3(name, &y, size));
        ch = channels(w, name);
    }
    let chw_to_hwc = |x: Vec<f32>, f: &dyn Fn(f32) -> f32| {
        let mut out = vec![0.0; x.len()];
        for c in 0..3 {
            for p in 0..size * size {
                out[p * 3 + c] = f(x[c * size * size + p]);
            }
        }
        out
    };
    let image_mean = chw_to_hwc(w.conv3x3("decoder.image.mean", &y, size), &sigmoid);
    let image_sigma = chw_to_hwc(w.conv3x3("decoder.image.sigma", &y, size), &|v| {
        bounded_sigma(v, floor)
    });
    let x = mlp(w, "decoder.joint.layers", shared);
    let joint_mean = w.linear("decoder.joint.mean", &x);
    let joint_sigma = w
        .linear("decoder.joint.sigma", &x)
        .into_iter()
        .map(|v| bounded_sigma(v, floor))
        .collect();
    [image_mean, image_sigma, joint_mean, joint_sigma]
}

#[test]
fn a_plain_reference_reproduces_the_golden_prediction() {
    let bytes = export_safetensors(golden::MODEL, false).unwrap();
    let file = SafeTensors::deserialize(&bytes).unwrap();
    let weights = Weights(
        file.tensors()
            .into_iter()
            .map(|(name, view)| {
                let values = support::f32_values(&name, &view);
                (name, (view.shape().to_vec(), values))
            })
            .collect(),
    );
    let (_, metadata) = SafeTensors::read_metadata(&bytes).unwrap();
    let header: serde_json::Value =
        serde_json::from_str(&metadata.metadata().as_ref().unwrap()["dmbn"]).unwrap();
    let config = &header["config"];
    assert_eq!(config["kind"], "dmbn", "this reference is DMBN's");
    assert_ne!(
        config["coarse_tail"], true,
        "this reference's tail is at full resolution"
    );
    let size = config["image_size"].as_u64().unwrap() as usize;
    let floor = config["sigma_floor"].as_f64().unwrap() as f32;
    let stat = |k: &str| -> Vec<f32> {
        let values = header["normalization"][k].as_array().unwrap();
        values.iter().map(|v| v.as_f64().unwrap() as f32).collect()
    };
    let (mean, std) = (stat("mean"), stat("std"));
    // A calibrated file's factors on the joint σ (`dmbn calibrate`), 1 without them: one
    // within the span of the observed steps, the forecast one (absent: the same) outside it.
    let between = header["joint_sigma_scale"].as_f64().unwrap_or(1.0) as f32;
    let forecast = header["forecast_joint_sigma_scale"]
        .as_f64()
        .map_or(between, |f| f as f32);
    let (first, last) = (golden::OBSERVE[0], *golden::OBSERVE.last().unwrap());
    let joint_sigma_scale = |k: usize| {
        if (first..=last).contains(&k) {
            between
        } else {
            forecast
        }
    };

    // The observations, encoded: [t plane, RGB in [0, 1]] and [t, normalised joints], each
    // modality averaged over the observations, then blended.
    let seq = episode(Action::Grasp, golden::SEED, size as u32).unwrap();
    let times = seq.times();
    let (mut image, mut joint) = (Vec::<Vec<f32>>::new(), Vec::<Vec<f32>>::new());
    for &k in &golden::OBSERVE {
        let mut planes = vec![times[k]; size * size];
        for c in 0..3 {
            planes.extend((0..size * size).map(|p| seq.frame(k)[p * 3 + c] as f32 / 255.0));
        }
        image.push(encode_image(&weights, planes, size));
        let normalised = (0..7).map(|j| (seq.joints[k][j] - mean[j]) / std[j]);
        joint.push(mlp(
            &weights,
            "joint_encoder.layers",
            std::iter::once(times[k]).chain(normalised).collect(),
        ));
    }
    let average = |z: &[Vec<f32>]| -> Vec<f32> {
        (0..z[0].len())
            .map(|i| z.iter().map(|v| v[i]).sum::<f32>() / z.len() as f32)
            .collect()
    };
    let c = golden::BLEND;
    let r: Vec<f32> = average(&image)
        .iter()
        .zip(average(&joint))
        .map(|(i, j)| c * i + (1.0 - c) * j)
        .collect();

    // Three target steps (first, middle, last) against their entries of the golden sample.
    let steps = seq.len();
    let sample = golden::expected();
    let px = size * size * 3;
    let stride = golden::STRIDE;
    let images_from = 2 * steps * 7;
    let sampled = |k: usize| (k * px..(k + 1) * px).filter(move |i| i % stride == 0);
    let per_image = (steps * px).div_ceil(stride);
    let mut worst = (0.0f32, String::new());
    let mut note = |what: String, got: f32, want: f32| {
        let diff = (got - want).abs();
        // (A NaN takes the place too, and fails the check below.)
        if diff.is_nan() || diff > worst.0 {
            worst = (diff, what);
        }
    };
    for k in [0, steps / 2, steps - 1] {
        let input: Vec<f32> = r.iter().copied().chain([times[k]]).collect();
        let [image_mean, image_sigma, joint_mean, joint_sigma] = decode(&weights, &input, floor);
        for j in 0..7 {
            let m = joint_mean[j] * std[j] + mean[j];
            let s = joint_sigma[j] * std[j] * joint_sigma_scale(k);
            note(format!("joint mean {k}/{j}"), m, sample[k * 7 + j]);
            note(format!("joint σ {k}/{j}"), s, sample[steps * 7 + k * 7 + j]);
        }
        for i in sampled(k) {
            let at = i / stride;
            let got = image_mean[i - k * px];
            note(format!("image mean {i}"), got, sample[images_from + at]);
            let got = image_sigma[i - k * px];
            note(
                format!("image σ {i}"),
                got,
                sample[images_from + per_image + at],
            );
        }
    }
    assert!(
        worst.0 < 1e-4,
        "the plain reference differs from tests/golden/prediction.json by {} at {}",
        worst.0,
        worst.1
    );
}

/// The scenario's (observed, scored) steps of a `len`-step sequence: `interp` `k` evenly spaced
/// observations, every step scored; `extrap` 3 observations over the first 30%, the rest scored.
fn scenario_steps(scenario: Scenario, len: usize, k: usize) -> (Vec<usize>, Vec<usize>) {
    let spread = |k: usize, last: usize| -> Vec<usize> {
        (0..k)
            .map(|i| (i as f64 * last as f64 / (k - 1) as f64).round() as usize)
            .collect()
    };
    match scenario {
        Scenario::Interp => (spread(k, len - 1), (0..len).collect()),
        Scenario::Extrap => {
            let last = ((0.3 * (len - 1) as f64).round() as usize).max(2);
            (spread(3, last), (last + 1..len).collect())
        }
    }
}

/// The trivial baseline at step `k`: the nearest observation's frame (the earlier one on a
/// tie) and the joints linearly interpolated between the observations around `k`, held
/// outside them.
fn baseline(seq: &dmbn::data::Sequence, observed: &[usize], k: usize) -> (usize, [f32; 7]) {
    let mut nearest = observed[0];
    for &o in observed {
        if o.abs_diff(k) < nearest.abs_diff(k) {
            nearest = o;
        }
    }
    let (first, last) = (observed[0], *observed.last().unwrap());
    let joints = if k <= first {
        seq.joints[first].try_into().unwrap()
    } else if k >= last {
        seq.joints[last].try_into().unwrap()
    } else {
        let after = observed.iter().position(|&o| o >= k).unwrap();
        let (a, b) = (observed[after - 1], observed[after]);
        let w = (k - a) as f32 / (b - a) as f32;
        std::array::from_fn(|j| (1.0 - w) * seq.joints[a][j] + w * seq.joints[b][j])
    };
    (nearest, joints)
}

/// Gaussian NLL of `x` under N(m, s²).
fn nll(x: f64, m: f64, s: f64) -> f64 {
    0.5 * (2.0 * std::f64::consts::PI).ln() + s.ln() + (x - m).powi(2) / (2.0 * s * s)
}

#[test]
fn a_plain_reference_reproduces_the_golden_scores() {
    let predictor = Predictor::from_bytes(golden_score::MODEL).unwrap();
    let std = predictor.normalization().std.clone();
    let seq = episode(Action::Grasp, golden_score::SEED, 64).unwrap();
    let (len, px) = (seq.len(), seq.frame_bytes());
    let expected = golden_score::expected();
    for (row, &scenario) in golden_score::SCENARIOS.iter().enumerate() {
        let (observed, scored) = scenario_steps(scenario, len, golden_score::OBSERVATIONS);
        let observations = Observations::from_sequence(&seq, &observed).unwrap();
        let p = predictor
            .predict(&observations, &seq.times(), golden_score::BLEND)
            .unwrap();
        // Per guess (model, baseline): squared arm-joint and pixel errors, absolute gripper
        // errors, NLL sums, over the scored and over the observed steps.
        let mut sums = [[0.0f64; 7]; 2];
        let [mut nll_image, mut nll_joint] = [0.0f64; 2];
        for k in 0..len {
            let (is_observed, is_scored) = (observed.contains(&k), scored.contains(&k));
            let (nearest, linear) = baseline(&seq, &observed, k);
            let truth = seq.frame(k);
            let guesses: [(&[f32], Vec<f32>); 2] = [
                (
                    &p.joint_mean[k * 7..k * 7 + 7],
                    p.image_mean[k * px..(k + 1) * px].to_vec(),
                ),
                (
                    &linear,
                    seq.frame(nearest)
                        .iter()
                        .map(|&v| v as f32 / 255.0)
                        .collect(),
                ),
            ];
            for (g, (joints, frame)) in guesses.iter().enumerate() {
                let joint_se: f64 = (0..6)
                    .map(|j| (joints[j] as f64 - seq.joints[k][j] as f64).powi(2))
                    .sum();
                let image_se: f64 = truth
                    .iter()
                    .zip(frame)
                    .map(|(&x, &m)| (x as f64 / 255.0 - m as f64).powi(2))
                    .sum();
                let s = &mut sums[g];
                if is_scored {
                    s[0] += joint_se;
                    s[1] += (joints[6] as f64 - seq.joints[k][6] as f64).abs();
                    s[2] += image_se;
                    s[3] += 1.0;
                }
                if is_observed {
                    s[4] += joint_se;
                    s[5] += image_se;
                    s[6] += 1.0;
                }
            }
            if is_scored {
                let sigma = &p.image_sigma[k * px..(k + 1) * px];
                let image: f64 = (0..px)
                    .map(|i| {
                        let m = p.image_mean[k * px + i] as f64;
                        nll(truth[i] as f64 / 255.0, m, sigma[i] as f64)
                    })
                    .sum();
                nll_image += image / px as f64;
                let joint: f64 = (0..7)
                    .map(|j| {
                        let s = std[j] as f64;
                        nll(
                            seq.joints[k][j] as f64 / s,
                            p.joint_mean[k * 7 + j] as f64 / s,
                            p.joint_sigma[k * 7 + j] as f64 / s,
                        )
                    })
                    .sum();
                nll_joint += joint / 7.0;
            }
        }
        for (g, s) in sums.iter().enumerate() {
            let measures = [
                (s[0] / (s[3] * 6.0)).sqrt(),
                s[1] / s[3],
                s[2] / (s[3] * px as f64),
                (s[4] / (s[6] * 6.0)).sqrt(),
                s[5] / (s[6] * px as f64),
            ];
            let want = &expected[row][g * 9..g * 9 + 5];
            for (i, (got, want)) in measures.iter().zip(want).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                    "{scenario} {} measure {i}: the reference gives {got}, score.json {want}",
                    ["model", "baseline"][g]
                );
            }
        }
        let steps = scored.len() as f64;
        for (i, got) in [(5, nll_image / steps), (6, nll_joint / steps)] {
            let want = expected[row][i];
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                "{scenario} model NLL {i}: the reference gives {got}, score.json {want}"
            );
        }
    }
}
