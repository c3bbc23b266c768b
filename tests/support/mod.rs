//! Helpers shared by the native integration tests (`mod support;`).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The original DMBN dataset, when present: `$DMBN2020` or `../shared/datasets/dmbn2020`.
/// Tests that need it print a note and pass without it; it is never part of the repository.
pub fn dmbn2020() -> Option<PathBuf> {
    let path = std::env::var_os("DMBN2020")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/datasets/dmbn2020")
        });
    path.is_dir().then_some(path)
}

/// The original DMBN dataset opened, or `None` after reporting the calling test as skipped.
pub fn dmbn2020_dataset() -> Option<dmbn::data::Dataset> {
    let Some(root) = dmbn2020() else {
        skip("no original DMBN data (set DMBN2020=path/to/data2020)");
        return None;
    };
    Some(dmbn::data::Dataset::open(&root).unwrap())
}

/// Reports the calling test as skipped for `reason`: on stderr, and as a line of the file
/// `$DMBN_SKIPPED` names (`.ci/run` counts them, so that the closing line says "N skipped"
/// instead of counting the test as passed). The test then returns without checking anything.
pub fn skip(reason: &str) {
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    eprintln!("skipped: {test}: {reason}");
    if let Some(file) = std::env::var_os("DMBN_SKIPPED") {
        use std::io::Write;
        let line = format!("{test}: {reason}\n");
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&file)
            .and_then(|mut f| f.write_all(line.as_bytes()));
        appended.expect("DMBN_SKIPPED names a writable file");
    }
}

/// A Python with torch and safetensors: `$DMBN_PYTHON`, the benchmark's venv
/// (`~/.cache/dmbn/venv`, made by bench/model.sh), or `python3`; without one, the calling
/// test is reported as skipped.
pub fn python_with_torch() -> Option<PathBuf> {
    let venv =
        std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/dmbn/venv/bin/python"));
    let candidates = std::env::var_os("DMBN_PYTHON")
        .map(PathBuf::from)
        .into_iter()
        .chain(venv)
        .chain([PathBuf::from("python3")]);
    for python in candidates {
        let ok = std::process::Command::new(&python)
            .args(["-c", "import torch, safetensors, numpy"])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Some(python);
        }
    }
    skip(
        "no Python with torch, safetensors and numpy (set DMBN_PYTHON, or run bench/model.sh once)",
    );
    None
}

/// `python` run in the repository's `python/` folder (where `-m dmbn_torch` and `import
/// dmbn_torch` find the PyTorch twin), writing no `__pycache__`.
pub fn twin(python: &Path) -> std::process::Command {
    let mut command = std::process::Command::new(python);
    command
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("python"))
        .env("PYTHONDONTWRITEBYTECODE", "1");
    command
}

/// A file of the repository's `assets/`.
pub fn asset(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(path)
}

/// Writes a dataset of simulated episodes at `root`: for every id and action, the episode of
/// seed `seed + id` at 64×64.
pub fn simulated_dataset(
    root: &Path,
    ids: impl IntoIterator<Item = u32>,
    actions: &[dmbn::sim::Action],
    seed: u64,
) {
    simulated_arm_dataset(root, dmbn::sim::Arm::Ur5, ids, actions, seed)
}

/// [`simulated_dataset`] of `arm`'s episodes.
pub fn simulated_arm_dataset(
    root: &Path,
    arm: dmbn::sim::Arm,
    ids: impl IntoIterator<Item = u32>,
    actions: &[dmbn::sim::Action],
    seed: u64,
) {
    let mut writer = dmbn::data::DatasetWriter::create(root).unwrap();
    for id in ids {
        for &action in actions {
            let episode = dmbn::sim::episode_with_arm(arm, action, seed + id as u64, 64).unwrap();
            writer.write(id, action.name(), &episode).unwrap();
        }
    }
    writer.finish().unwrap();
}

/// `train`'s settings for a run that only has to end with a model file of the data's shape: a
/// DMBN-PTE, 2 steps of 2 sequences, a third of a tiny dataset validating, no quality check.
pub const TRAIN_TWO_STEPS: [&str; 12] = [
    "--model",
    "pte",
    "--steps",
    "2",
    "--batch",
    "2",
    "--val-every",
    "2",
    "--val-fraction",
    "0.34",
    "--quality-sequences",
    "0",
];

/// Writes `model` as a model file at `path` (what `train` writes).
pub fn save_model(
    path: &Path,
    model: &dmbn::model::Model,
    normalization: &dmbn::model::Normalization,
    half: bool,
) {
    let bytes = dmbn::model::save_bytes(model, normalization, half).unwrap();
    dmbn::data::write_atomic(path, &bytes).unwrap();
}

/// The model's, the baseline's and the mean motion's measures over `seqs` (`(action,
/// sequence)`) in `scenario`: 5 observations (interp), both modalities blended half and half.
pub fn measure(
    predictor: &dmbn::predict::Predictor,
    seqs: &[(&str, dmbn::data::Sequence)],
    scenario: dmbn::quality::Scenario,
    mean: &dmbn::quality::MeanMotion,
) -> (
    dmbn::quality::Quality,
    dmbn::quality::Quality,
    dmbn::quality::Quality,
) {
    measure_blended(predictor, seqs, scenario, 0.5, mean)
}

/// [`measure`] with blending coefficient `blend` (1: frames alone).
pub fn measure_blended(
    predictor: &dmbn::predict::Predictor,
    seqs: &[(&str, dmbn::data::Sequence)],
    scenario: dmbn::quality::Scenario,
    blend: f32,
    mean: &dmbn::quality::MeanMotion,
) -> (
    dmbn::quality::Quality,
    dmbn::quality::Quality,
    dmbn::quality::Quality,
) {
    use dmbn::quality::{score_sequence, Accumulator, SequenceScores};
    let mut acc = SequenceScores {
        mean_motion: Some(Accumulator::default()),
        ..Default::default()
    };
    for (action, seq) in seqs {
        let s = score_sequence(predictor, seq, action, scenario, 5, blend, Some(mean))
            .unwrap()
            .unwrap();
        acc.model.merge(&s.model);
        acc.baseline.merge(&s.baseline);
        acc.mean_motion
            .as_mut()
            .unwrap()
            .merge(s.mean_motion.as_ref().unwrap());
    }
    (
        acc.model.finish(),
        acc.baseline.finish(),
        acc.mean_motion.unwrap().finish(),
    )
}

/// An untrained model of `kind` (seeded), with `normalization`.
pub fn untrained(
    kind: dmbn::model::ModelKind,
    normalization: dmbn::data::Normalization,
) -> dmbn::predict::Predictor {
    let device = burn::tensor::Device::flex();
    device.seed(5);
    let model = dmbn::model::ModelConfig::new(kind).init(&device).unwrap();
    model.draw_weights();
    dmbn::predict::Predictor::new(model, normalization)
}

/// Asserts that `predictor` (the file `name`) reads its observations on `seqs` (interp, 5
/// observations): its joint RMSE and image MSE, over every step and at the observed steps,
/// below 0.8× the action's mean motion's (`mean`) and below 0.8× `untrained`'s. Both ~0
/// passes the second: the attentive model returns its observed joints by construction,
/// trained or not (a model that ignores its observations cannot).
pub fn assert_uses_its_observations(
    name: &str,
    predictor: &dmbn::predict::Predictor,
    untrained: &dmbn::predict::Predictor,
    seqs: &[(&str, dmbn::data::Sequence)],
    mean: &dmbn::quality::MeanMotion,
) {
    use dmbn::quality::{Quality, Scenario};
    let (model, _, motion) = measure(predictor, seqs, Scenario::Interp, mean);
    let (fresh, _, _) = measure(untrained, seqs, Scenario::Interp, mean);
    println!("{name}: {model:?}\nmean motion: {motion:?}");
    let by = |q: &Quality| {
        [
            ("joint RMSE", q.joint_rmse),
            ("joint RMSE at the observed steps", q.observed_joint_rmse),
            ("image MSE", q.image_mse),
            ("image MSE at the observed steps", q.observed_image_mse),
        ]
    };
    let rows = by(&model).into_iter().zip(by(&motion)).zip(by(&fresh));
    for (((what, got), (_, motion)), (_, fresh)) in rows {
        assert!(
            got < 0.8 * motion,
            "{name}: {what} {got:.5}, the mean motion's {motion:.5}"
        );
        assert!(
            got < 0.8 * fresh || got.max(fresh) < 1e-6,
            "{name}: {what} {got:.5}, an untrained model's {fresh:.5}"
        );
    }
}

/// The values of an f32 safetensors tensor (panics, naming it, on another dtype).
#[cfg(not(target_arch = "wasm32"))]
pub fn f32_values(name: &str, view: &safetensors::tensor::TensorView) -> Vec<f32> {
    assert_eq!(view.dtype(), safetensors::Dtype::F32, "{name}");
    view.data()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Every tensor of safetensors bytes as f32 values, by name (u8 tensors widened).
#[cfg(not(target_arch = "wasm32"))]
pub fn safetensors_values(bytes: &[u8]) -> std::collections::HashMap<String, Vec<f32>> {
    let file = safetensors::SafeTensors::deserialize(bytes).unwrap();
    file.tensors()
        .into_iter()
        .map(|(name, view)| {
            let values = match view.dtype() {
                safetensors::Dtype::U8 => view.data().iter().map(|&b| f32::from(b)).collect(),
                _ => f32_values(&name, &view),
            };
            (name, values)
        })
        .collect()
}

/// The original-data issue's calibration bar for `predictor` (`name` in the messages) on
/// `seqs`: in each scenario, the fraction of true joint values within mean ± 2σ at the
/// unobserved steps, printed, and a message for each outside 90-98% (a calibrated Gaussian:
/// 95.4%).
pub fn two_sigma_misses(
    name: &str,
    predictor: &dmbn::predict::Predictor,
    seqs: &[(&str, dmbn::data::Sequence)],
    mean: &dmbn::quality::MeanMotion,
) -> Vec<String> {
    let mut misses = Vec::new();
    for scenario in dmbn::quality::Scenario::ALL {
        let (model, _, _) = measure(predictor, seqs, scenario, mean);
        let joints = model
            .calibration
            .and_then(|c| c.joints)
            .expect("unobserved joints were scored");
        println!("{name} {scenario}: ±2σ {:.3}", joints.two_sigma);
        if !(0.90..=0.98).contains(&joints.two_sigma) {
            misses.push(format!(
                "{name} {scenario}: ±2σ holds {:.1}% of {} joint values",
                100.0 * joints.two_sigma,
                joints.values
            ));
        }
    }
    misses
}

/// The rows of `joints` as fixed `[f32; JOINTS]` arrays (the simulator's arm, trajectories):
/// panics unless the table is `JOINTS` values wide.
pub fn fixed_rows(joints: &dmbn::data::Joints) -> Vec<[f32; dmbn::data::JOINTS]> {
    joints
        .rows()
        .map(|r| r.try_into().expect("JOINTS values a row"))
        .collect()
}

/// A model file's `bytes` with its header's `key` set to `value`, the weights and their
/// checksum kept: a file that lies about itself, for the reader's checks.
pub fn with_header_field(bytes: &[u8], key: &str, value: serde_json::Value) -> Vec<u8> {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + len]).unwrap();
    header[key] = value;
    let header = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&bytes[16 + len..]);
    out
}
