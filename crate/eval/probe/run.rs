//! The probe itself: encode, fit the heads over the seeds, collect the report.
use std::time::Instant;

use burn::tensor::Device;

use super::checks::{diverged, time_variance, DIVERGENCE_FACTOR};
use super::encodings::encode_steps;
use super::head::{fit_head, HeadConfig};
use super::report::{divergence_warning, Divergence, ProbeReport, ProbeResult, ProbeRow};
use crate::data::Sequence;
use crate::eval::mean_ci95;
use crate::model::{ModelConfig, ModelError, ModelKind};
use crate::predict::Predictor;

/// How the probe runs.
#[derive(Debug, Clone)]
pub struct ProbeConfig {
    /// Seeds (head initialisation and batches; the Random row's encoder).
    pub seeds: u64,
    pub head: HeadConfig,
}

/// The time-regression probe: for each row and each modality encoder, freeze the encoder, fit
/// a head regressing the context time from its encodings of `train` steps, and measure the MSE
/// on `test` steps, over `config.seeds` seeds. `dmbn` must be a DMBN, `pte` a DMBN-PTE, both
/// for the same frame size. Heads that diverge ([`diverged`]) are listed in their row and in
/// the report's warnings; whether the split is big enough is the caller's to check
/// ([`split_warnings`](super::split_warnings): only it knows the ids). `progress` hears what is being done.
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
