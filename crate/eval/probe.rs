use std::time::Instant;

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use rand::seq::index;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;

use super::standardizer::Standardizer;
use super::{mean_ci95, MeanCi};
use crate::augment::{planar, Batch};
use crate::data::{Normalization, Sequence, JOINTS};
use crate::model::{tensors, Model, ModelConfig, ModelError, ModelKind};
use crate::predict::Predictor;

/// Every step of some sequences encoded as a single context, per modality: the probe's data.
#[derive(Debug, Clone, PartialEq)]
pub struct Encodings {
    /// H: encoding width.
    pub hidden: usize,
    /// `K × H`: image context encodings.
    pub image: Vec<f32>,
    /// `K × H`: joint context encodings.
    pub joint: Vec<f32>,
    /// `K`: the true time (phase) of every step.
    pub times: Vec<f32>,
}

/// Steps encoded per forward pass.
const ENCODE_CHUNK: usize = 64;

/// Encodes every step of `seqs` as a one-context set with `model`'s encoders (DMBN: e_m(t, x);
/// DMBN-PTE: g_m(e_m(x) + P(t))), joints normalised with `normalization`. With `zero_time`
/// the encoders are fed t = 0 instead of the step's time (the probe's Null row); the
/// returned `times` are always the true ones.
pub fn encode_steps(
    model: &Model,
    normalization: &Normalization,
    seqs: &[Sequence],
    zero_time: bool,
) -> Result<Encodings, ModelError> {
    let device = Device::flex();
    let s = model.image_size();
    let px = 3 * s * s;
    let steps: Vec<(&Sequence, usize, f32)> = seqs
        .iter()
        .flat_map(|seq| {
            let times = seq.times();
            (0..seq.len()).map(move |k| (seq, k, times[k]))
        })
        .collect();
    let mut out = Encodings {
        hidden: 0,
        image: Vec::new(),
        joint: Vec::new(),
        times: Vec::new(),
    };
    for chunk in steps.chunks(ENCODE_CHUNK) {
        let b = chunk.len();
        let mut batch = Batch {
            batch: b,
            contexts: 1,
            targets: 1,
            image_size: s,
            context_images: vec![0.0; b * px],
            context_joints: Vec::with_capacity(b * JOINTS),
            context_times: Vec::with_capacity(b),
            context_mask: vec![1.0; b],
            target_images: Vec::new(),
            target_joints: Vec::new(),
            target_times: vec![0.0; b],
            blend: vec![0.5; b],
        };
        for (i, &(seq, k, t)) in chunk.iter().enumerate() {
            planar(
                seq.frame(k),
                s,
                &mut batch.context_images[i * px..(i + 1) * px],
            );
            batch
                .context_joints
                .extend(normalization.normalize(&seq.joints[k]));
            batch.context_times.push(if zero_time { 0.0 } else { t });
            out.times.push(t);
        }
        let z = model.encode_contexts(&tensors(&batch, &device)?)?;
        out.hidden = z.image.dims()[2];
        out.image.extend(read(z.image));
        out.joint.extend(read(z.joint));
    }
    Ok(out)
}

fn read<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .try_to_vec::<f32>()
        .unwrap_or_default()
}

/// The probe's regression head and how it is fitted.
#[derive(Config, Debug)]
pub struct HeadConfig {
    /// Hidden units of the one-hidden-layer head.
    #[config(default = 64)]
    pub hidden: usize,
    /// Adam steps.
    #[config(default = 1500)]
    pub steps: usize,
    /// Encodings per step.
    #[config(default = 256)]
    pub batch: usize,
    /// Adam learning rate.
    #[config(default = 1e-3)]
    pub lr: f64,
}

/// A small fully connected head: encoding → ReLU hidden layer → time.
#[derive(Module, Debug)]
struct Head {
    hidden: Linear,
    out: Linear,
}

impl Head {
    fn forward(&self, x: Tensor<2>) -> Tensor<2> {
        self.out.forward(relu(self.hidden.forward(x)))
    }
}

/// Fits a head that regresses the time from `train` encodings (features standardised with the
/// training statistics, robustly: see [`super::REL_STD_FLOOR`] and [`super::STANDARD_CLIP`])
/// and returns its mean squared error on `test`. `image` picks the image or the joint
/// encodings. Deterministic for a seed; NaN when either set is empty or the widths differ.
pub fn fit_head(
    train: &Encodings,
    test: &Encodings,
    image: bool,
    config: &HeadConfig,
    seed: u64,
) -> f64 {
    let pick = |e: &Encodings| {
        if image {
            e.image.clone()
        } else {
            e.joint.clone()
        }
    };
    let h = train.hidden;
    let (mut x_train, mut x_test) = (pick(train), pick(test));
    let (n, k) = (train.times.len(), test.times.len());
    if h == 0
        || n == 0
        || k == 0
        || test.hidden != h
        || x_train.len() != n * h
        || x_test.len() != k * h
        || config.hidden == 0
    {
        return f64::NAN;
    }
    // Standardise: the encoders' scales differ by orders of magnitude between models.
    let standardizer = Standardizer::fit(&x_train, h);
    standardizer.apply(&mut x_train, false);
    standardizer.apply(&mut x_test, true);
    let device = Device::flex().autodiff();
    device.seed(seed);
    let mut head = Head {
        hidden: LinearConfig::new(h, config.hidden).init(&device),
        out: LinearConfig::new(config.hidden, 1).init(&device),
    };
    let mut optim = AdamConfig::new().init();
    let mut rng = Pcg64::seed_from_u64(seed);
    let batch = config.batch.clamp(1, n);
    for _ in 0..config.steps {
        let rows = index::sample(&mut rng, train.times.len(), batch).into_vec();
        let x: Vec<f32> = rows
            .iter()
            .flat_map(|&r| x_train[r * h..(r + 1) * h].to_vec())
            .collect();
        let t: Vec<f32> = rows.iter().map(|&r| train.times[r]).collect();
        let x = Tensor::<2>::from_data(TensorData::new(x, [batch, h]), &device);
        let t = Tensor::<2>::from_data(TensorData::new(t, [batch, 1]), &device);
        let loss = (head.forward(x) - t).square().mean();
        let grads = GradientsParams::from_grads(loss.backward(), &head);
        head = optim.step(config.lr, head, grads);
    }
    let head = head.valid();
    let plain = Device::flex();
    let x = Tensor::<2>::from_data(TensorData::new(x_test, [k, h]), &plain);
    let t = Tensor::<2>::from_data(TensorData::new(test.times.clone(), [k, 1]), &plain);
    read((head.forward(x) - t).square().mean())
        .first()
        .map_or(f64::NAN, |&v| v as f64)
}

/// The rows of the paper's Table 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ProbeRow {
    /// The trained DMBN's encoders fed t = 0: what the content alone tells.
    Null,
    /// An untrained DMBN of the same architecture (a new one per seed).
    Random,
    /// The trained DMBN.
    Dmbn,
    /// The trained DMBN-PTE (z = g(e(x) + P(t))).
    #[serde(rename = "DMBN-PTE")]
    Pte,
}

impl ProbeRow {
    pub const ALL: [ProbeRow; 4] = [
        ProbeRow::Null,
        ProbeRow::Random,
        ProbeRow::Dmbn,
        ProbeRow::Pte,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ProbeRow::Null => "Null",
            ProbeRow::Random => "Random",
            ProbeRow::Dmbn => "DMBN",
            ProbeRow::Pte => "DMBN-PTE",
        }
    }
}

/// How the probe runs.
#[derive(Debug, Clone)]
pub struct ProbeConfig {
    /// Seeds (head initialisation and batches; the Random row's encoder).
    pub seeds: u64,
    pub head: HeadConfig,
}

/// A head counts as diverged when its test MSE is above this many times Var(t) of the test
/// steps (what predicting the mean time scores), or is not finite.
pub const DIVERGENCE_FACTOR: f64 = 2.0;
/// Fewer test ids than this make the probe's numbers anecdotal: a warning.
pub const MIN_TEST_IDS: usize = 3;
/// Fewer test steps than this: a warning.
pub const MIN_TEST_STEPS: usize = 100;
/// Fewer training ids than this: a warning (the heads can memorise them).
pub const MIN_TRAIN_IDS: usize = 5;

/// True when a head of test MSE `mse` has diverged (or overfit): not finite, or above
/// [`DIVERGENCE_FACTOR`] × `var_t`, `var_t` being the variance of the test times.
pub fn diverged(mse: f64, var_t: f64) -> bool {
    !mse.is_finite() || mse > DIVERGENCE_FACTOR * var_t
}

/// Population variance of `times` (NaN for none).
pub fn time_variance(times: &[f32]) -> f64 {
    if times.is_empty() {
        return f64::NAN;
    }
    let n = times.len() as f64;
    let mean = times.iter().map(|&t| t as f64).sum::<f64>() / n;
    times
        .iter()
        .map(|&t| (t as f64 - mean).powi(2))
        .sum::<f64>()
        / n
}

/// The warnings a split of `train_ids` ids (`train_steps` steps) and `test_ids` ids
/// (`test_steps` steps) deserves: too few test ids ([`MIN_TEST_IDS`]), test steps
/// ([`MIN_TEST_STEPS`]) or training ids ([`MIN_TRAIN_IDS`]). Empty when it is big enough.
pub fn split_warnings(
    train_ids: usize,
    train_steps: usize,
    test_ids: usize,
    test_steps: usize,
) -> Vec<String> {
    let mut out = Vec::new();
    let advice = "use more ids (--test-fraction, --test-ids or --test-data)";
    if test_ids < MIN_TEST_IDS {
        out.push(format!(
            "only {test_ids} test id(s) (fewer than {MIN_TEST_IDS}): the MSEs describe those \
             sequences rather than the encoders, and the CIs cover only the seeds; {advice}"
        ));
    }
    if test_steps < MIN_TEST_STEPS {
        out.push(format!(
            "only {test_steps} test steps (fewer than {MIN_TEST_STEPS}): the MSEs are noisy; \
             {advice}"
        ));
    }
    if train_ids < MIN_TRAIN_IDS {
        out.push(format!(
            "only {train_ids} training id(s) ({train_steps} steps; fewer than {MIN_TRAIN_IDS} \
             ids): the heads can memorise them and fail on the test ids; {advice}"
        ));
    }
    out
}

/// A head that diverged (see [`diverged`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Divergence {
    /// `"image"` or `"joint"`.
    pub modality: &'static str,
    pub seed: u64,
    /// Its test MSE.
    pub mse: f64,
}

/// One row of the table: test MSE of the time regression per seed, and its mean with CI.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeResult {
    pub row: ProbeRow,
    pub image: MeanCi,
    pub joint: MeanCi,
    pub image_mse: Vec<f64>,
    pub joint_mse: Vec<f64>,
    /// The heads that diverged: their cells are not to be trusted.
    pub diverged: Vec<Divergence>,
}

impl ProbeResult {
    /// The seeds whose `modality` (`"image"` / `"joint"`) head diverged.
    pub fn diverged_seeds(&self, modality: &str) -> Vec<u64> {
        self.diverged
            .iter()
            .filter(|d| d.modality == modality)
            .map(|d| d.seed)
            .collect()
    }
}

/// Everything the probe measured.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeReport {
    pub rows: Vec<ProbeResult>,
    pub train_sequences: usize,
    pub test_sequences: usize,
    pub train_steps: usize,
    pub test_steps: usize,
    /// Variance of the test steps' times: the MSE of predicting their mean time.
    pub test_time_variance: f64,
    /// MSE above which a head counts as diverged ([`DIVERGENCE_FACTOR`] × the variance).
    pub divergence_limit: f64,
    pub seeds: u64,
    pub seconds: f64,
    /// Everything that makes numbers of this run doubtful: diverged heads (from [`probe`]),
    /// a split too small ([`split_warnings`], added by the caller that knows the ids).
    pub warnings: Vec<String>,
}

/// MSE ×1e-3 with two decimals.
fn milli(v: f64) -> String {
    format!("{:.2}", v * 1e3)
}

impl ProbeReport {
    /// The table in the paper's layout: MSE ×1e-3, mean (95% CI low, high); cells with a
    /// diverged head marked ⚠; then Var(t) of the test steps and the warnings.
    pub fn markdown(&self) -> String {
        let cell = |m: &MeanCi, flagged: bool| {
            format!(
                "{} ({}, {}){}",
                milli(m.mean),
                milli(m.mean - m.ci95),
                milli(m.mean + m.ci95),
                if flagged { " ⚠" } else { "" }
            )
        };
        let mut out = String::from(
            "| Model | Image Encoder Loss (1e-3) | Joint Encoder Loss (1e-3) |\n|---|---:|---:|\n",
        );
        for r in &self.rows {
            out.push_str(&format!(
                "| {} | {} | {} |\n",
                r.row.name(),
                cell(&r.image, !r.diverged_seeds("image").is_empty()),
                cell(&r.joint, !r.diverged_seeds("joint").is_empty())
            ));
        }
        out.push_str(&format!(
            "\nVar(t) of the {} test steps: {} ×1e-3 (the MSE of predicting the mean time); a \
             head above {} ×1e-3 ({DIVERGENCE_FACTOR}×Var(t)) counts as diverged (⚠).\n",
            self.test_steps,
            milli(self.test_time_variance),
            milli(self.divergence_limit)
        ));
        if !self.warnings.is_empty() {
            out.push_str("\nWarnings:\n\n");
            for w in &self.warnings {
                out.push_str(&format!("- {w}\n"));
            }
        }
        out
    }
}

/// The warning for the diverged heads of `r`'s `modality`, if any.
fn divergence_warning(
    r: &ProbeResult,
    modality: &'static str,
    seeds: u64,
    var_t: f64,
) -> Option<String> {
    let bad: Vec<&Divergence> = r
        .diverged
        .iter()
        .filter(|d| d.modality == modality)
        .collect();
    if bad.is_empty() {
        return None;
    }
    let worst =
        bad.iter().map(|d| d.mse).fold(
            f64::NEG_INFINITY,
            |a, b| if b.is_nan() || b > a { b } else { a },
        );
    let cell = if modality == "image" {
        r.image
    } else {
        r.joint
    };
    Some(format!(
        "{} {modality}: {} of {seeds} heads diverged (seeds {:?}; test MSE up to {} ×1e-3, \
         cell mean {} ±{} ×1e-3) — above {DIVERGENCE_FACTOR}×Var(t) = {} ×1e-3, where \
         predicting the mean time scores Var(t) = {} ×1e-3; the heads overfit the training \
         encodings or extrapolated, so this cell says nothing about the encoder",
        r.row.name(),
        bad.len(),
        bad.iter().map(|d| d.seed).collect::<Vec<_>>(),
        milli(worst),
        milli(cell.mean),
        milli(cell.ci95),
        milli(DIVERGENCE_FACTOR * var_t),
        milli(var_t),
    ))
}

/// The time-regression probe: for each row and each modality encoder, freeze the encoder, fit
/// a head regressing the context time from its encodings of `train` steps, and measure the MSE
/// on `test` steps, over `config.seeds` seeds. `dmbn` must be a DMBN, `pte` a DMBN-PTE, both
/// for the same frame size. Heads that diverge ([`diverged`]) are listed in their row and in
/// the report's warnings; whether the split is big enough is the caller's to check
/// ([`split_warnings`]: only it knows the ids). `progress` hears what is being done.
pub fn probe(
    dmbn: &Predictor,
    pte: &Predictor,
    train: &[Sequence],
    test: &[Sequence],
    config: &ProbeConfig,
    mut progress: impl FnMut(&str),
) -> Result<ProbeReport, ModelError> {
    for (p, kind) in [(dmbn, ModelKind::Dmbn), (pte, ModelKind::Pte)] {
        if p.model().kind() != kind {
            return Err(ModelError::Kind {
                expected: kind.to_string(),
                found: p.model().kind().to_string(),
            });
        }
    }
    let train_steps: usize = train.iter().map(Sequence::len).sum();
    let test_steps: usize = test.iter().map(Sequence::len).sum();
    for (field, steps) in [
        ("probe training set", train_steps),
        ("probe test set", test_steps),
    ] {
        if steps == 0 {
            return Err(ModelError::Config {
                field,
                reason: "holds no steps: the probe fits heads on the training steps and \
                         scores them on the test steps"
                    .into(),
            });
        }
    }
    let test_times: Vec<f32> = test.iter().flat_map(Sequence::times).collect();
    let var_t = time_variance(&test_times);
    let start = Instant::now();
    let size = dmbn.model().image_size();
    let mut rows = Vec::new();
    let mut warnings = Vec::new();
    for row in ProbeRow::ALL {
        let (mut image_mse, mut joint_mse) = (Vec::new(), Vec::new());
        let mut bad = Vec::new();
        let fixed = match row {
            ProbeRow::Null => Some((dmbn, true)),
            ProbeRow::Dmbn => Some((dmbn, false)),
            ProbeRow::Pte => Some((pte, false)),
            ProbeRow::Random => None,
        };
        let fixed = match fixed {
            Some((p, zero)) => {
                progress(&format!(
                    "{}: encoding {} + {} sequences",
                    row.name(),
                    train.len(),
                    test.len()
                ));
                Some((
                    encode_steps(p.model(), p.normalization(), train, zero)?,
                    encode_steps(p.model(), p.normalization(), test, zero)?,
                ))
            }
            None => None,
        };
        for seed in 0..config.seeds {
            let (tr, te) = match &fixed {
                Some(pair) => (pair.0.clone(), pair.1.clone()),
                None => {
                    progress(&format!("Random: encoding with untrained encoder {seed}"));
                    let device = Device::flex();
                    device.seed(seed);
                    let model = ModelConfig::new(ModelKind::Dmbn)
                        .with_image_size(size)
                        .init(&device)?;
                    let norm = dmbn.normalization();
                    (
                        encode_steps(&model, norm, train, false)?,
                        encode_steps(&model, norm, test, false)?,
                    )
                }
            };
            progress(&format!("{}: fitting heads, seed {seed}", row.name()));
            for (image, modality, mses) in [
                (true, "image", &mut image_mse),
                (false, "joint", &mut joint_mse),
            ] {
                let mse = fit_head(&tr, &te, image, &config.head, seed);
                if diverged(mse, var_t) {
                    bad.push(Divergence {
                        modality,
                        seed,
                        mse,
                    });
                }
                mses.push(mse);
            }
        }
        let result = ProbeResult {
            row,
            image: mean_ci95(&image_mse),
            joint: mean_ci95(&joint_mse),
            image_mse,
            joint_mse,
            diverged: bad,
        };
        for modality in ["image", "joint"] {
            if let Some(w) = divergence_warning(&result, modality, config.seeds, var_t) {
                warnings.push(w);
            }
        }
        rows.push(result);
    }
    Ok(ProbeReport {
        rows,
        train_sequences: train.len(),
        test_sequences: test.len(),
        train_steps,
        test_steps,
        test_time_variance: var_t,
        divergence_limit: DIVERGENCE_FACTOR * var_t,
        seeds: config.seeds,
        seconds: start.elapsed().as_secs_f64(),
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn divergence_and_split_thresholds() {
        assert!(diverged(0.2, 0.08) && diverged(f64::NAN, 0.08) && !diverged(0.1, 0.08));
        assert!((time_variance(&[0.0, 1.0]) - 0.25).abs() < 1e-12);
        assert!(split_warnings(5, 500, 3, 100).is_empty());
        assert_eq!(split_warnings(4, 500, 2, 99).len(), 3);
    }
}
