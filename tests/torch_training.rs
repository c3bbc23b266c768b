//! The PyTorch twin's training (python/dmbn_torch/) against the Rust trainer, wherever a
//! Python with torch is installed (otherwise each test is reported as skipped): the twin reads
//! a dataset as the Rust reader does; on one batch and one set of weights it computes the loss
//! and every gradient trainer.rs `step()` does; two DDP processes (gloo, on the CPU) take the
//! steps one process takes; and what it trains, `dmbn import` reads. Native only.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use burn::module::{Module, ModuleMapper, Param};
use burn::optim::GradientsParams;
use burn::tensor::{Device, Tensor};
use dmbn::augment::{Batch, JointTargets, Sampler, SamplerConfig};
use dmbn::data::{Dataset, DatasetWriter, JointScale, Normalization, JOINTS};
use dmbn::model::{
    export_safetensors, import_file, joint_nll, joint_target_tensors, save_bytes, tensors,
    LossValues, Model, ModelConfig, ModelKind,
};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::Action;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use safetensors::tensor::TensorView;
use safetensors::Dtype;

/// Runs `command`, failing the test with its output unless it succeeds; returns its stdout.
fn run(command: &mut Command) -> String {
    let out = command.output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{command:?}\n{stdout}\n{stderr}");
    stdout.into_owned()
}

/// The largest absolute difference between two equally long lists.
fn max_diff(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// A safetensors file of f32 arrays (name, shape, values) with `metadata` as its `dmbn` entry.
fn write_arrays(path: &Path, arrays: &[(&str, Vec<usize>, &[f32])], metadata: &str) {
    let bytes: Vec<Vec<u8>> = arrays
        .iter()
        .map(|(_, _, v)| v.iter().flat_map(|x| x.to_le_bytes()).collect())
        .collect();
    let views: Vec<(&str, TensorView)> = arrays
        .iter()
        .zip(&bytes)
        .map(|((name, shape, _), b)| {
            (
                *name,
                TensorView::new(Dtype::F32, shape.clone(), b).unwrap(),
            )
        })
        .collect();
    let metadata = HashMap::from([("dmbn".to_string(), metadata.to_string())]);
    std::fs::write(path, safetensors::serialize(views, Some(metadata)).unwrap()).unwrap();
}

#[test]
fn the_twin_reads_a_dataset_as_the_rust_reader_does() {
    let Some(python) = support::python_with_torch() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("data");
    // 128-px frames: read at 128 (as stored), 64 (an exact area average) and 96 (image's
    // triangle filter).
    let mut writer = DatasetWriter::create(&root).unwrap();
    let episode = dmbn::sim::episode(Action::Move, 11, 128).unwrap();
    writer.write(4, "move", &episode).unwrap();
    writer.finish().unwrap();
    let dataset = Dataset::open(&root).unwrap();
    let script = "import sys, numpy as np, torch\n\
        from safetensors.torch import save_file\n\
        from dmbn_torch import data\n\
        (id, _, folder), = data.sequences(sys.argv[1])\n\
        out = {}\n\
        for size in (128, 64, 96):\n    \
            s = data.read_sequence(folder, id, size)\n    \
            out[f'frames_{size}'] = torch.from_numpy(s.frames.copy())\n\
        out['joints'] = torch.from_numpy(s.joints)\n\
        for scale in ('per-joint', 'shared'):\n    \
            n = data.Normalization.fit([s.joints]).scaled(scale)\n    \
            out[f'std_{scale}'] = torch.from_numpy(n.std.copy())\n\
        save_file(out, sys.argv[2])\n";
    let read = dir.path().join("read.safetensors");
    run(support::twin(&python)
        .args(["-c", script])
        .arg(&root)
        .arg(&read));
    let twin = support::safetensors_values(&std::fs::read(&read).unwrap());
    for size in [128, 64, 96] {
        let seq = dataset.read(&dataset.sequences()[0], Some(size)).unwrap();
        let frames: Vec<f32> = seq.frames.iter().map(|&b| f32::from(b)).collect();
        let theirs = &twin[&format!("frames_{size}")];
        let off = frames.iter().zip(theirs).filter(|(a, b)| a != b).count();
        let worst = max_diff(&frames, theirs);
        println!(
            "{size} px: {off} of {} values differ, by at most {worst}",
            frames.len()
        );
        if size == 96 {
            // The triangle filter in another summation order: a level at most, rarely.
            assert!(worst <= 1.0 && off * 1000 < frames.len(), "{size} px");
        } else {
            assert_eq!(off, 0, "{size} px frames differ");
        }
        let joints: Vec<f32> = seq.joints.values().to_vec();
        assert_eq!(joints, twin["joints"]);
    }
    // The joint normalisation, fitted per joint or with the arm's one scale.
    let seq = dataset.read(&dataset.sequences()[0], None).unwrap();
    for (scale, name) in [
        (JointScale::PerJoint, "per-joint"),
        (JointScale::Shared, "shared"),
    ] {
        let ours = Normalization::fit(JOINTS, &seq.joints).scaled(scale).std;
        let theirs = &twin[&format!("std_{name}")];
        assert!(
            max_diff(&ours, theirs) < 1e-6,
            "{name}: {ours:?} {theirs:?}"
        );
    }
}

/// Every parameter replaced by its gradient (zero where it has none): exported like weights,
/// the gradients get the PyTorch names and layouts.
struct ToGradients<'a>(&'a GradientsParams);

impl ModuleMapper for ToGradients<'_> {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        let (id, tensor, _) = param.consume();
        let grad = self.0.get::<D>(id).unwrap_or_else(|| tensor.zeros_like());
        Param::initialized(id, grad)
    }
}

/// The loss settings of the parity batch.
const BETA: f64 = 0.5;
const JOINT_WEIGHT: f64 = 0.3;
const DRAWN_FRAME_WEIGHT: f64 = 0.2;

/// What trainer.rs `step()` computes before the optimiser: the loss of one batch (with its
/// joint-only targets and the drawn frame's error) and the gradients of every weight.
fn step_gradients(
    model: &Model,
    batch: &Batch,
    joint_targets: &JointTargets,
    device: &Device,
) -> (LossValues, GradientsParams) {
    let batch = tensors(batch, device).unwrap();
    let representation = model.encode(&batch).unwrap();
    let prediction = model
        .decode(&representation, batch.target_times.clone())
        .unwrap();
    let mut loss = model.loss(&prediction, &batch, BETA).unwrap();
    if let (Some(drawn), Some(frames)) = (&prediction.image_drawn, &batch.target_images) {
        let mse = (drawn.clone() - frames.clone()).square().mean();
        loss.total = loss.total + mse.mul_scalar(DRAWN_FRAME_WEIGHT);
    }
    let (times, joints) = joint_target_tensors(joint_targets, JOINTS, device).unwrap();
    let (mean, sigma) = model.decode_joints(&representation, times).unwrap();
    loss.total = loss.total + joint_nll(mean, sigma, joints, BETA).mul_scalar(JOINT_WEIGHT);
    let values = loss.values();
    (
        values,
        GradientsParams::from_grads(loss.total.backward(), model),
    )
}

#[test]
fn the_twin_computes_the_loss_and_gradients_the_rust_trainer_does() {
    let Some(python) = support::python_with_torch() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("data");
    support::simulated_dataset(&root, 0..2, &[Action::Grasp, Action::Move], 20);
    let dataset = Dataset::open(&root).unwrap();
    let pool: Vec<_> = dataset
        .sequences()
        .iter()
        .map(|s| dataset.read(s, Some(64)).unwrap())
        .collect();
    let normalization = Normalization::fit(JOINTS, pool.iter().flat_map(|s| s.joints.rows()));
    let sampler = Sampler::new(SamplerConfig {
        batch: 2,
        max_contexts: 3,
        targets: 3,
        contexts_in_targets: true,
        joint_targets: 2,
        single_modality: 0.0,
        prefix_contexts: 0.0,
        warp: None,
    });
    let device = Device::flex().autodiff();
    for (i, kind) in ModelKind::ALL.into_iter().enumerate() {
        let (mut batch, joint_targets) =
            sampler.sample_with_joints(&pool, &normalization, &mut Pcg64::seed_from_u64(i as u64));
        // Both modalities blended, and frames alone (the attentive model then starts its
        // joints from those it reads from the frames).
        batch.blend = vec![0.35, if kind == ModelKind::Attn { 1.0 } else { 0.8 }];
        device.seed(40 + i as u64);
        let config = ModelConfig::new(kind)
            .with_joint_weight(JOINT_WEIGHT)
            .with_frame_joints((kind == ModelKind::Attn).then_some(true));
        let model = config.init(&device).unwrap();
        model.draw_weights();
        let (values, grads) = step_gradients(&model, &batch, &joint_targets, &device);
        let gradients = model.clone().map(&mut ToGradients(&grads));
        let export = |m: &Model| {
            export_safetensors(&save_bytes(m, &normalization, false).unwrap(), false).unwrap()
        };
        let (weights, rust_grads) = (dir.path().join("weights.safetensors"), export(&gradients));
        std::fs::write(&weights, export(&model)).unwrap();
        let (b, n, m, s) = (batch.batch, batch.contexts, batch.targets, batch.image_size);
        let batch_file = dir.path().join("batch.safetensors");
        write_arrays(
            &batch_file,
            &[
                ("context_images", vec![b, n, 3, s, s], &batch.context_images),
                ("context_joints", vec![b, n, 7], &batch.context_joints),
                ("context_times", vec![b, n], &batch.context_times),
                ("context_mask", vec![b, n], &batch.context_mask),
                ("target_images", vec![b, m, 3, s, s], &batch.target_images),
                ("target_joints", vec![b, m, 7], &batch.target_joints),
                ("target_times", vec![b, m], &batch.target_times),
                ("blend", vec![b], &batch.blend),
                ("joint_target_times", vec![b, 2], &joint_targets.times),
                ("joint_target_joints", vec![b, 2, 7], &joint_targets.joints),
            ],
            &format!(
                r#"{{"beta": {BETA}, "joint_weight": {JOINT_WEIGHT}, "drawn_frame_weight": {DRAWN_FRAME_WEIGHT}}}"#
            ),
        );
        let out = dir.path().join("twin.safetensors");
        run(support::twin(&python)
            .args([
                "-c",
                "import sys\nfrom dmbn_torch.loss import gradients\ngradients(*sys.argv[1:])",
            ])
            .arg(&weights)
            .arg(&batch_file)
            .arg(&out));
        let twin = support::safetensors_values(&std::fs::read(&out).unwrap());
        let rust = support::safetensors_values(&rust_grads);
        let want = [
            values.total,
            values.image_nll,
            values.joint_nll,
            values.image_mse,
            values.joint_mse,
        ];
        // Relative to the part's size (as the goldens compare): the image NLL sums thousands
        // of f32 terms, a loss near 4 agrees to about 3e-5 of itself.
        let loss_diff = want
            .iter()
            .zip(&twin["loss"])
            .map(|(a, b)| (a - b).abs() / b.abs().max(1.0))
            .fold(0.0, f32::max);
        // Every gradient, named as exported: the twin has exactly these tensors.
        assert_eq!(twin.len() - 1, rust.len(), "{kind}: tensor names");
        let (mut worst, mut worst_name, mut largest) = (0.0f32, String::new(), 0.0f32);
        for (name, grad) in &rust {
            let theirs = twin
                .get(name)
                .unwrap_or_else(|| panic!("{kind}: no gradient {name}"));
            let diff = max_diff(grad, theirs);
            if std::env::var_os("DMBN_PARITY_ALL").is_some() {
                let top = grad.iter().fold(0.0f32, |a, g| a.max(g.abs()));
                println!("  {kind} {name}: {diff:.2e} of |g| up to {top:.2e}");
            }
            largest = grad.iter().fold(largest, |a, g| a.max(g.abs()));
            if diff > worst {
                (worst, worst_name) = (diff, name.clone());
            }
        }
        let line = format!(
            "{kind}: loss {:.6} (largest relative difference of the five parts {loss_diff:.2e}), {} \
             gradients, largest |g| {largest:.3e}, largest difference {worst:.2e} ({worst_name})",
            values.total,
            rust.len()
        );
        println!("{line}");
        assert!(loss_diff <= 1e-4, "{line}");
        assert!(worst <= 1e-4, "{line}");
    }
}

#[test]
fn two_ddp_processes_take_the_steps_of_one_a_resumed_run_too_and_dmbn_imports_the_result() {
    let Some(python) = support::python_with_torch() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("data");
    support::simulated_dataset(&root, 0..3, &[Action::Grasp], 30);
    // 3 steps (a run of 2 resumed to 3: the step schedule, ×0.3 every third of the run, is the
    // same for both).
    let train = |out: &Path, processes: &[&str], steps: &str, resume: bool| {
        let mut command = support::twin(&python);
        command
            .env("OMP_NUM_THREADS", "1")
            .args(processes)
            .args(["-m", "dmbn_torch.train", "--out"])
            .arg(out)
            .args(["--steps", steps]);
        if resume {
            command.arg("--resume");
        } else {
            command
                .args(["--model", "pte", "--device", "cpu", "--batch", "4"])
                .args(["--max-contexts", "3", "--targets-per-sequence", "2"])
                .args([
                    "--joint-targets",
                    "2",
                    "--seed",
                    "3",
                    "--lr",
                    "1e-3",
                    "--augment",
                ])
                .args(["--beta-nll", "1", "--schedule", "step", "--val-every", "3"])
                .args(["--checkpoint-every", "2", "--data"])
                .arg(&root);
        }
        run(&mut command)
    };
    let (one, two, part) = (
        dir.path().join("one"),
        dir.path().join("two"),
        dir.path().join("part"),
    );
    let said = train(&one, &[], "3", false);
    assert!(
        said.contains("1 process;") && said.contains("step 3/3"),
        "{said}"
    );
    let said = train(
        &two,
        &[
            "-m",
            "torch.distributed.run",
            "--standalone",
            "--nproc_per_node",
            "2",
        ],
        "3",
        false,
    );
    assert!(said.contains("2 processes;"), "{said}");
    train(&part, &[], "2", false);
    let said = train(&part, &[], "3", true);
    assert!(said.contains("step 3/3"), "{said}");

    // The same weights after 3 steps, up to float summation order.
    let read = |run: &Path| {
        support::safetensors_values(&std::fs::read(run.join("model.safetensors")).unwrap())
    };
    let (a, b, resumed) = (read(&one), read(&two), read(&part));
    assert_eq!(a.len(), b.len());
    let worst = a
        .iter()
        .map(|(name, values)| max_diff(values, &b[name]))
        .fold(0.0, f32::max);
    assert!(
        a.iter().all(|(name, values)| values == &resumed[name]),
        "a run resumed from its checkpoint ends elsewhere"
    );
    let metrics = |run: &Path| std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    let losses = |run: &Path| -> Vec<f64> {
        metrics(run)
            .lines()
            .map(|l| {
                serde_json::from_str::<serde_json::Value>(l).unwrap()["loss"]
                    .as_f64()
                    .unwrap()
            })
            .collect()
    };
    let (la, lb) = (losses(&one), losses(&two));
    assert_eq!(la, losses(&part), "the resumed run's metrics.jsonl");
    println!("one process {la:?}, two {lb:?}; largest weight difference {worst:.2e}");
    assert_eq!(la.len(), 3);
    for (x, y) in la.iter().zip(&lb) {
        assert!(
            (x - y).abs() < 1e-4 * x.abs().max(1.0),
            "losses {la:?} vs {lb:?}"
        );
    }
    assert!(worst < 1e-5, "two processes' weights differ by {worst}");
    assert!(one.join("checkpoint.pt").exists() && !one.join("checkpoint.pt.tmp").exists());

    // `dmbn import` reads what the twin trained, with the joint statistics of the training
    // ids (0 and 1; id 2 held out), as the Rust trainer fits them.
    let bytes = import_file(&one.join("model.safetensors"), false).unwrap();
    let header = dmbn::model::read_header(&bytes).unwrap();
    let dataset = Dataset::open(&root).unwrap();
    let training: Vec<_> = dataset.sequences()[..2]
        .iter()
        .map(|s| dataset.read(s, Some(64)).unwrap())
        .collect();
    let fitted = Normalization::fit(JOINTS, training.iter().flat_map(|s| s.joints.rows()));
    assert_eq!(header.config.kind, ModelKind::Pte);
    for (x, y) in header.normalization.mean.iter().zip(fitted.mean) {
        assert!((x - y).abs() <= 1e-6 * y.abs().max(1.0), "{x} vs {y}");
    }
    let held = dataset.read(&dataset.sequences()[2], Some(64)).unwrap();
    let obs = Observations::from_sequence(&held, &[0, 20, 40]).unwrap();
    let prediction = Predictor::from_bytes(&bytes)
        .unwrap()
        .predict(&obs, &held.times(), 0.5)
        .unwrap();
    assert!(prediction.joint_mean.iter().all(|v| v.is_finite()));
}
