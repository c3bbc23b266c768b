//! The mirror stage: a fresh one predicts the interpolated reads and only frames-only
//! predictions use it, it survives the model file, bad files are refused, fitting it lowers
//! the error of the reads' interpolation, and `train --mirror` adds one to a model file.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use burn::tensor::Device;
use dmbn::data::{Joints, Sequence, JOINTS};
use dmbn::model::{self, Mirror, MirrorConfig, ModelError};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};
use dmbn::train::{fit_mirror, MirrorExamples, MirrorFit};
use rand::SeedableRng;

/// The page's default model file with its network alone (`stage`: none) or with `stage`.
fn shipped_with(stage: Option<Mirror>) -> Vec<u8> {
    let bytes = std::fs::read(support::asset("models/attn-sim.dmbn")).unwrap();
    let (model, header) = model::load_with_header(&bytes, &Device::flex(), None, None).unwrap();
    let model = match stage {
        Some(stage) => model.with_mirror(stage),
        None => model.without_mirror(),
    };
    let bytes = model::save_bytes(&model, &header.normalization, false).unwrap();
    model::with_joint_sigma_scale(&bytes, header.joint_sigma_scales()).unwrap()
}

/// The page's default network with a fresh (zero-correction) stage, and its file's bytes.
fn with_fresh_stage() -> (Predictor, Vec<u8>) {
    let bytes = shipped_with(Some(MirrorConfig::new().init(&Device::flex())));
    (Predictor::from_bytes(&bytes).unwrap(), bytes)
}

/// The page's default network alone.
fn network_only() -> Predictor {
    Predictor::from_bytes(&shipped_with(None)).unwrap()
}

fn interpolate(times: &[f32], reads: &Joints, t: f32) -> [f32; JOINTS] {
    let i = times.partition_point(|&s| s <= t).clamp(1, times.len() - 1);
    let w = ((t - times[i - 1]) / (times[i] - times[i - 1])).clamp(0.0, 1.0);
    std::array::from_fn(|j| reads[i - 1][j] + w * (reads[i][j] - reads[i - 1][j]))
}

#[test]
fn a_fresh_stage_predicts_the_reads_interpolated_and_only_from_frames_alone() {
    let (predictor, _) = with_fresh_stage();
    let plain = network_only();
    let demo = episode(Action::Move, 700, 64).unwrap();
    let t = demo.len();
    let steps = [0, t / 4, t / 2, 3 * t / 4, t - 1];
    let observed = Observations::from_sequence(&demo, &steps).unwrap();
    let reads = predictor.reads(&observed).unwrap();
    assert_eq!(
        reads,
        plain.reads(&observed).unwrap(),
        "the network's own reads"
    );
    let times = demo.times();
    let joints = predictor.predict_joints(&observed, &times, 1.0).unwrap();
    let full = predictor.predict(&observed, &times[..30], 1.0).unwrap();
    for (k, &time) in times.iter().enumerate() {
        let want = interpolate(&observed.times, &reads, time);
        for j in 0..JOINTS {
            assert!((joints[k][j] - want[j]).abs() < 1e-5, "step {k} joint {j}");
            if k < 30 {
                assert!((full.joint_mean[k * JOINTS + j] - want[j]).abs() < 1e-4);
            }
        }
    }
    assert!(full.joint_sigma.iter().all(|&s| s > 0.0 && s.is_finite()));
    // Blended observations are the network's alone, frames and all.
    let blended = predictor.predict(&observed, &times[..30], 0.5).unwrap();
    assert_eq!(
        blended,
        plain.predict(&observed, &times[..30], 0.5).unwrap()
    );
    assert_ne!(
        predictor.predict_joints(&observed, &times, 1.0).unwrap(),
        plain.predict_joints(&observed, &times, 1.0).unwrap(),
        "frames alone, the stage answers"
    );
    assert_eq!(
        full.image_mean,
        plain
            .predict(&observed, &times[..30], 1.0)
            .unwrap()
            .image_mean,
        "the frames are the network's"
    );
}

#[test]
fn the_page_s_default_model_ships_with_a_stage_that_corrects_its_network() {
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    assert!(shipped.model().mirror.is_some());
    let plain = network_only();
    let demo = episode(Action::Move, 701, 64).unwrap();
    let t = demo.len();
    let observed =
        Observations::from_sequence(&demo, &[0, t / 4, t / 2, 3 * t / 4, t - 1]).unwrap();
    let times = demo.times();
    let (a, b) = (
        shipped.predict_joints(&observed, &times, 1.0).unwrap(),
        plain.predict_joints(&observed, &times, 1.0).unwrap(),
    );
    let apart = a
        .rows()
        .zip(&b)
        .flat_map(|(x, y)| x.iter().zip(y))
        .map(|(x, y)| (x - y).abs());
    assert!(
        apart.fold(0.0f32, f32::max) > 1e-3,
        "the stage corrects the network"
    );
}

#[test]
fn the_stage_survives_the_file_and_bad_files_are_refused() {
    let (predictor, bytes) = with_fresh_stage();
    let header = model::read_header(&bytes).unwrap();
    assert_eq!(header.config.mirror, Some(256));
    let again = Predictor::from_bytes(&bytes).unwrap();
    let demo = episode(Action::Grasp, 701, 64).unwrap();
    let observed = Observations::from_sequence(&demo, &[0, 20, 40]).unwrap();
    let times = demo.times();
    assert_eq!(
        predictor.predict_joints(&observed, &times, 1.0).unwrap(),
        again.predict_joints(&observed, &times, 1.0).unwrap()
    );
    // A header that promises a stage the weights lack, or weights with a stage the header
    // does not name.
    let plain = shipped_with(None);
    let (model, header) = model::load_with_header(&plain, &Device::flex(), None, None).unwrap();
    let promised = header.config.clone().with_mirror(Some(256));
    let lying = replace_config(&plain, &serde_json::to_value(&promised).unwrap());
    let err = Predictor::from_bytes(&lying).unwrap_err().to_string();
    assert!(err.contains("mirror"), "{err}");
    let unnamed = replace_config(&bytes, &serde_json::to_value(model.config()).unwrap());
    let err = Predictor::from_bytes(&unnamed).unwrap_err().to_string();
    assert!(err.contains("mirror"), "{err}");
    let zero = replace_config(
        &bytes,
        &serde_json::to_value(header.config.with_mirror(Some(0))).unwrap(),
    );
    let err = Predictor::from_bytes(&zero).unwrap_err();
    assert!(
        matches!(
            err,
            ModelError::Config {
                field: "mirror",
                ..
            }
        ),
        "{err}"
    );
}

/// `bytes` with the header's config replaced by `config` (the weights and checksum kept).
fn replace_config(bytes: &[u8], config: &serde_json::Value) -> Vec<u8> {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + len]).unwrap();
    header["config"] = config.clone();
    let header = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&bytes[16 + len..]);
    out
}

/// The mean squared error of the reads' interpolation over `examples`.
fn interpolation_mse(examples: &MirrorExamples) -> f64 {
    let se: f64 = examples
        .start
        .iter()
        .zip(&examples.truth)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum();
    se / examples.truth.len() as f64
}

#[test]
fn fitting_the_stage_lowers_the_error_of_the_interpolated_reads() {
    let plain = network_only();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let mut examples = MirrorExamples::new(JOINTS);
    let demos: Vec<Sequence> = (0..4)
        .flat_map(|i| Action::ALL.map(|a| episode(a, 800 + i, 64).unwrap()))
        .collect();
    for demo in &demos {
        examples.add(&plain, demo, 2, &mut rng).unwrap();
    }
    let most = 2 * demos.iter().map(Sequence::len).sum::<usize>();
    assert!(
        examples.rows() > most / 4 && examples.rows() <= most,
        "the steps from the first glimpse to the last: {} of {most}",
        examples.rows()
    );
    let fit = MirrorFit {
        width: 32,
        draws: 2,
        steps: 400,
        batch: 128,
        lr: 3e-3,
        seed: 1,
    };
    let mut last = None;
    let mirror = fit_mirror(&examples, None, fit, &Device::flex().autodiff(), |p| {
        last = Some(p)
    })
    .unwrap();
    let last = last.expect("progress at the end");
    assert_eq!(last.step, 400);
    let before = interpolation_mse(&examples).sqrt();
    assert!(
        last.rmse < 0.8 * before,
        "the stage's RMSE {} against the interpolation's {before}",
        last.rmse
    );
    assert_eq!(mirror.width(), 32);
    let empty = MirrorExamples::new(JOINTS);
    let err = fit_mirror(&empty, None, fit, &Device::flex().autodiff(), |_| {}).unwrap_err();
    assert!(err.to_string().contains("no training examples"), "{err}");
}

#[test]
fn train_mirror_adds_a_stage_to_a_model_file() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..4, &Action::ALL, 900);
    let out = tmp.path().join("run");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_train"))
        .args([
            "--steps",
            "0",
            "--quality-sequences",
            "0",
            "--val-fraction",
            "0.25",
        ])
        .args([
            "--mirror",
            "--mirror-steps",
            "50",
            "--mirror-draws",
            "1",
            "--mirror-width",
            "16",
        ])
        .arg("--init")
        .arg(support::asset("models/attn-sim.dmbn"))
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("fitting the mirror stage: 6 training and 2 validation"),
        "{stderr}"
    );
    let bytes = std::fs::read(out.join("model.dmbn")).unwrap();
    let header = model::read_header(&bytes).unwrap();
    assert_eq!(header.config.mirror, Some(16));
    let shipped =
        model::read_header(&std::fs::read(support::asset("models/attn-sim.dmbn")).unwrap())
            .unwrap();
    assert!(shipped.joint_sigma_scale.is_some());
    assert_eq!(
        header.joint_sigma_scales(),
        shipped.joint_sigma_scales(),
        "the network as it was: its σ scales are kept"
    );
    assert_eq!(header.weights.dtype, shipped.weights.dtype);
    Predictor::from_bytes(&bytes).unwrap();
    // Without a model to fit to, or with nothing to read.
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_train"))
        .args(["--steps", "0", "--mirror", "--mirror-draws", "0"])
        .arg("--init")
        .arg(support::asset("models/attn-sim.dmbn"))
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(tmp.path().join("bad"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success());
    assert!(stderr.contains("mirror_draws"), "{stderr}");
}

#[test]
fn calibrating_frames_only_predictions_of_a_file_with_a_stage_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..1, &[Action::Grasp], 910);
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .arg("calibrate")
        .arg("--model")
        .arg(support::asset("models/attn-sim.dmbn"))
        .arg("--data")
        .arg(&data)
        .args(["--ids", "0-0", "--blend", "1", "--out"])
        .arg(tmp.path().join("out.dmbn"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("mirror stage") && stderr.contains("blend below 1"),
        "{stderr}"
    );
    assert!(!tmp.path().join("out.dmbn").exists());
}
