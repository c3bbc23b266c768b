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
/// training statistics) and returns its mean squared error on `test`. `modality` picks the
/// image or the joint encodings. Deterministic for a seed.
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
    // Standardise: the encoders' scales differ by orders of magnitude between models.
    let n = train.times.len().max(1);
    for j in 0..h {
        let col = x_train.iter().skip(j).step_by(h);
        let mean = col.clone().sum::<f32>() / n as f32;
        let var = col.map(|v| (v - mean).powi(2)).sum::<f32>() / n as f32;
        let std = if var > 1e-12 { var.sqrt() } else { 1.0 };
        for x in [&mut x_train, &mut x_test] {
            x.iter_mut()
                .skip(j)
                .step_by(h)
                .for_each(|v| *v = (*v - mean) / std);
        }
    }
    let device = Device::flex().autodiff();
    device.seed(seed);
    let mut head = Head {
        hidden: LinearConfig::new(h, config.hidden).init(&device),
        out: LinearConfig::new(config.hidden, 1).init(&device),
    };
    let mut optim = AdamConfig::new().init();
    let mut rng = Pcg64::seed_from_u64(seed);
    let batch = config.batch.min(train.times.len());
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
    let k = test.times.len();
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

/// One row of the table: test MSE of the time regression per seed, and its mean with CI.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeResult {
    pub row: ProbeRow,
    pub image: MeanCi,
    pub joint: MeanCi,
    pub image_mse: Vec<f64>,
    pub joint_mse: Vec<f64>,
}

/// Everything the probe measured.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeReport {
    pub rows: Vec<ProbeResult>,
    pub train_steps: usize,
    pub test_steps: usize,
    pub seeds: u64,
    pub seconds: f64,
}

impl ProbeReport {
    /// The table in the paper's layout: MSE ×1e-3, mean (95% CI low, high).
    pub fn markdown(&self) -> String {
        let cell = |m: &MeanCi| {
            format!(
                "{:.2} ({:.2}, {:.2})",
                m.mean * 1e3,
                (m.mean - m.ci95) * 1e3,
                (m.mean + m.ci95) * 1e3
            )
        };
        let mut out = String::from(
            "| Model | Image Encoder Loss (1e-3) | Joint Encoder Loss (1e-3) |\n|---|---:|---:|\n",
        );
        for r in &self.rows {
            out.push_str(&format!(
                "| {} | {} | {} |\n",
                r.row.name(),
                cell(&r.image),
                cell(&r.joint)
            ));
        }
        out
    }
}

/// The time-regression probe: for each row and each modality encoder, freeze the encoder, fit
/// a head regressing the context time from its encodings of `train` steps, and measure the MSE
/// on `test` steps, over `config.seeds` seeds. `dmbn` must be a DMBN, `pte` a DMBN-PTE, both
/// for the same frame size. `progress` hears what is being done.
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
    let start = Instant::now();
    let size = dmbn.model().image_size();
    let mut rows = Vec::new();
    for row in ProbeRow::ALL {
        let (mut image_mse, mut joint_mse) = (Vec::new(), Vec::new());
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
            image_mse.push(fit_head(&tr, &te, true, &config.head, seed));
            joint_mse.push(fit_head(&tr, &te, false, &config.head, seed));
        }
        rows.push(ProbeResult {
            row,
            image: mean_ci95(&image_mse),
            joint: mean_ci95(&joint_mse),
            image_mse,
            joint_mse,
        });
    }
    Ok(ProbeReport {
        rows,
        train_steps: train.iter().map(Sequence::len).sum(),
        test_steps: test.iter().map(Sequence::len).sum(),
        seeds: config.seeds,
        seconds: start.elapsed().as_secs_f64(),
    })
}
