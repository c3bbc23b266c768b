//! The joint stage: a fresh one predicts the interpolated reads and only frames-only
//! predictions and sampled futures (between the observations and the drawn steps, passing
//! through them) use it, it survives the model file, bad files are refused, fitting it lowers
//! the error of the reads' interpolation on demonstrations it did not see, the shipped one
//! beats its network on unseen demonstrations (joints and pushes), and `train --joint-stage`
//! adds one to a model file.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use burn::tensor::{Device, Tensor, TensorData};
use dmbn::data::{Joints, JOINTS};
use dmbn::futures::{draw_futures, trajectories, Sampling};
use dmbn::imitate::{imitate, Task};
use dmbn::model::{self, JointStage, JointStageConfig, ModelError};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};
use dmbn::train::{fit_joint_stage, JointStageExamples, JointStageFit};
use rand::SeedableRng;

/// The page's default model file with its network alone (`stage`: none) or with `stage`.
fn shipped_with(stage: Option<JointStage>) -> Vec<u8> {
    let bytes = std::fs::read(support::asset("models/attn-sim.dmbn")).unwrap();
    let (model, header) = model::load_with_header(&bytes, &Device::flex(), None, None).unwrap();
    let model = match stage {
        Some(stage) => model.with_joint_stage(stage),
        None => model.without_joint_stage(),
    };
    let bytes = model::save_bytes(&model, &header.normalization, false).unwrap();
    model::with_joint_sigma_scale(&bytes, header.joint_sigma_scales()).unwrap()
}

/// The page's default network with a fresh (zero-correction) stage, and its file's bytes.
fn with_fresh_stage() -> (Predictor, Vec<u8>) {
    let bytes = shipped_with(Some(JointStageConfig::new().init(&Device::flex())));
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
fn a_sampled_future_s_joints_come_from_the_stage_whatever_the_blend() {
    let (predictor, _) = with_fresh_stage();
    let plain = network_only();
    let demo = episode(Action::Move, 702, 64).unwrap();
    let t = demo.len();
    let observed = Observations::from_sequence(&demo, &[0, t / 7, 3 * t / 10]).unwrap();
    let times = demo.times();
    let future = &times[3 * t / 10 + 1..];
    let sampling = Sampling {
        samples: 3,
        oversample: 1,
        ..Sampling::default()
    };
    let futures = draw_futures(&predictor, &observed, future, 0.5, &sampling).unwrap();
    let rows = trajectories(&predictor, &futures, future).unwrap();
    for (f, rows) in futures.iter().zip(&rows) {
        // The stage reads each observed time the future conditions on (its bootstrap resample
        // repeats some) and each drawn step once.
        let reads = f.encoding.reads.as_ref().expect("a future's reads");
        let mut order: Vec<usize> = (0..reads.times.len()).collect();
        order.sort_by(|&a, &b| reads.times[a].total_cmp(&reads.times[b]));
        let sorted: Vec<f32> = order.iter().map(|&i| reads.times[i]).collect();
        assert!(sorted.windows(2).all(|w| w[0] < w[1]), "{sorted:?}");
        assert_eq!(sorted[sorted.len() - 1], future[future.len() - 1]);
        assert!(f.drawn.iter().all(|(u, _)| sorted.contains(u)));
        assert!(
            sorted.contains(&observed.times[2]),
            "the latest observation"
        );
        let joints = Joints::from_slices(JOINTS, order.iter().map(|&i| reads.joints.row(i)));
        // A fresh stage interpolates the reads: the future's joints at every imagined step.
        for (k, &time) in future.iter().enumerate() {
            let want = interpolate(&sorted, &joints, time);
            for j in 0..JOINTS {
                assert!((rows[k][j] - want[j]).abs() < 1e-5, "step {k} joint {j}");
            }
        }
    }
    // The network alone draws the same steps but decodes its own joints between them.
    let alone = draw_futures(&plain, &observed, future, 0.5, &sampling).unwrap();
    assert!(alone.iter().all(|f| f.encoding.reads.is_none()));
    let drawn =
        |fs: &[dmbn::futures::Future]| -> Vec<_> { fs.iter().map(|f| f.drawn.clone()).collect() };
    assert_eq!(drawn(&alone), drawn(&futures));
    let alone_rows = trajectories(&plain, &alone, future).unwrap();
    assert_ne!(alone_rows, rows);
    // Told not to, the stage stays out: the network's own joints.
    let without = Sampling {
        stage: false,
        ..sampling
    };
    let off = draw_futures(&predictor, &observed, future, 0.5, &without).unwrap();
    assert!(off.iter().all(|f| f.encoding.reads.is_none()));
    assert_eq!(trajectories(&predictor, &off, future).unwrap(), alone_rows);
    let frames_only = draw_futures(&predictor, &observed, future, 1.0, &without).unwrap();
    assert!(frames_only.iter().all(|f| f.encoding.reads.is_none()));
}

#[test]
fn through_its_reads_the_stage_moves_none_of_them_and_shapes_the_path_between() {
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let stage = shipped.model().joint_stage().unwrap();
    let demo = episode(Action::Grasp, 703, 64).unwrap();
    let t = demo.len();
    let steps = [0, t / 7, 3 * t / 10, 13 * t / 20, t - 1];
    let reads = shipped
        .reads(&Observations::from_sequence(&demo, &steps).unwrap())
        .unwrap();
    let times: Vec<f32> = steps.iter().map(|&k| demo.times()[k]).collect();
    let device = Device::flex();
    let (corrected, _) = stage.predict(&times, &reads, &times, &device);
    let (through, _) = stage.predict_through(&times, &reads, &times, &device);
    let apart = |a: &Joints, b: &Joints| {
        (a.rows().zip(b.rows()))
            .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
            .fold(0.0f32, f32::max)
    };
    assert!(apart(&corrected, &reads) > 1e-3, "the stage corrects reads");
    assert!(
        apart(&through, &reads) < 1e-5,
        "through them, it moves none"
    );
    // Between them, the stage's shape less its corrections interpolated: apart from the
    // straight line between the reads (what a fresh stage gives).
    let between = demo.times()[t / 2];
    let (path, _) = stage.predict_through(&times, &reads, &[between], &device);
    let line = interpolate(&times, &reads, between);
    assert!(path[0].iter().zip(line).any(|(p, l)| (p - l).abs() > 1e-3));
}

#[test]
fn the_page_s_default_model_ships_with_a_stage_that_corrects_its_network() {
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    assert!(shipped.model().joint_stage().is_some());
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
    // does not name: both named by the stage's key in the file, `mirror`.
    let plain = shipped_with(None);
    let (model, header) = model::load_with_header(&plain, &Device::flex(), None, None).unwrap();
    let promised = header.config.clone().with_mirror(Some(256));
    let lying =
        support::with_header_field(&plain, "config", serde_json::to_value(&promised).unwrap());
    let err = Predictor::from_bytes(&lying).unwrap_err().to_string();
    assert!(err.contains("mirror"), "{err}");
    let unnamed = support::with_header_field(
        &bytes,
        "config",
        serde_json::to_value(model.config()).unwrap(),
    );
    let err = Predictor::from_bytes(&unnamed).unwrap_err().to_string();
    assert!(err.contains("mirror"), "{err}");
    let zero = support::with_header_field(
        &bytes,
        "config",
        serde_json::to_value(header.config.with_mirror(Some(0))).unwrap(),
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

/// The mean squared error of the reads' interpolation over `examples`.
fn interpolation_mse(examples: &JointStageExamples) -> f64 {
    let se: f64 = examples
        .start
        .iter()
        .zip(&examples.truth)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum();
    se / examples.truth.len() as f64
}

/// The network's reads of `per_action` demonstrations of each action (simulator seeds `seed`
/// on), each at `draws` glimpse layouts, as the stage's examples; and the demonstrations'
/// steps, all layouts counted.
fn reads_of(
    plain: &Predictor,
    seed: u64,
    per_action: u64,
    draws: usize,
) -> (JointStageExamples, usize) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let (mut examples, mut steps) = (JointStageExamples::new(JOINTS), 0);
    for i in 0..per_action {
        for action in Action::ALL {
            let demo = episode(action, seed + i, 64).unwrap();
            examples.add(plain, &demo, draws, &mut rng).unwrap();
            steps += draws * demo.len();
        }
    }
    (examples, steps)
}

/// The RMSE of `stage`'s mean joints over `examples` (every joint value).
fn stage_rmse(stage: &JointStage, examples: &JointStageExamples, device: &Device) -> f64 {
    let (rows, d) = (examples.rows(), examples.joints);
    let tensor = |values: &[f32], width: usize| {
        Tensor::from_data(TensorData::new(values.to_vec(), [rows, width]), device)
    };
    let (mean, _) = stage.forward(
        tensor(&examples.x, examples.features()),
        tensor(&examples.start, d),
    );
    let se: f64 = model::values(mean)
        .iter()
        .zip(&examples.truth)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum();
    (se / examples.truth.len() as f64).sqrt()
}

/// Fitting the stage lowers the error of the interpolated reads on demonstrations it never
/// saw: a small stage (width 32, 400 steps) fitted on the network's reads of 20
/// demonstrations per action (3 glimpse layouts each) errs on 10 other demonstrations per
/// action, at layouts of their own, at most 0.8× as much as their reads' interpolation.
/// Measured (2026-12-07): 0.0586 against 0.1092 rad (0.54×; on its training reads 0.0372
/// against 0.0713); 0.53-0.70× over six other draws of the layouts. The bar is on unseen
/// demonstrations because on its training reads any fit looks good: fitted on 4-6
/// demonstrations per action the stage got to 0.2-0.4× there, but ranged 0.74-1.18× on
/// unseen ones.
#[test]
fn fitting_the_stage_lowers_the_error_of_the_interpolated_reads_on_unseen_demonstrations() {
    let plain = network_only();
    let (train, most) = reads_of(&plain, 800, 20, 3);
    let (held_out, _) = reads_of(&plain, 5_800, 10, 3);
    assert!(
        train.rows() > most / 4 && train.rows() <= most,
        "the steps from the first glimpse to the last: {} of {most}",
        train.rows()
    );
    let fit = JointStageFit {
        width: 32,
        draws: 3,
        steps: 400,
        batch: 128,
        lr: 3e-3,
        seed: 1,
    };
    let device = Device::flex().autodiff();
    let mut last = None;
    let stage = fit_joint_stage(&train, None, fit, &device, |p| last = Some(p)).unwrap();
    let last = last.expect("progress at the end");
    assert_eq!(last.step, 400);
    assert_eq!(stage.width(), 32);
    let (interpolated, corrected) = (
        interpolation_mse(&held_out).sqrt(),
        stage_rmse(&stage, &held_out, &device),
    );
    println!(
        "held out: the stage's RMSE {corrected:.4} against the interpolation's {interpolated:.4} \
         (training reads: {:.4} against {:.4})",
        stage_rmse(&stage, &train, &device),
        interpolation_mse(&train).sqrt()
    );
    assert!(
        corrected < 0.8 * interpolated,
        "on unseen demonstrations the stage's RMSE {corrected} against the interpolation's \
         {interpolated}"
    );
    let empty = JointStageExamples::new(JOINTS);
    let err = fit_joint_stage(&empty, None, fit, &device, |_| {}).unwrap_err();
    assert!(err.to_string().contains("no training examples"), "{err}");
}

/// The stage the page's default file ships with beats its network on unseen demonstrations:
/// 40 per action (simulator seeds 2,000,000 on; the network trained on seeds 1000-2999, the
/// stage on the network's reads of those, σ was calibrated on 700000-700029), imitated from 5
/// evenly spaced frames (blend 1, as `dmbn imitate --task frames`): with its stage the file
/// performs joints closer to the demonstrations' than its network alone, at most 0.85× its
/// joint RMSE, lands more pushes and carries at least as many grasps. Measured (2026-12-07):
/// joint RMSE 0.0264 against 0.0350 rad (0.75×; at 20, 30 and 50 per action 0.75-0.76×),
/// pushes 37 against 32 of 40 (46 against 38 of 50), grasps 38 against 33 (47 against 42).
#[test]
fn the_shipped_stage_beats_its_network_on_unseen_demonstrations() {
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let plain = network_only();
    // Per file: successes per action (grasp, move), the joints' squared error and values.
    let mut tally = [([0usize; 2], 0.0f64, 0usize); 2];
    for i in 0..40 {
        for (a, action) in Action::ALL.into_iter().enumerate() {
            let demo = episode(action, 2_000_000 + i, 64).unwrap();
            for (predictor, (successes, se, values)) in
                [&shipped, &plain].into_iter().zip(&mut tally)
            {
                let done = imitate(predictor, &demo, action, Task::Frames, 5, 1.0)
                    .unwrap()
                    .expect("long enough for 5 glimpses");
                successes[a] += usize::from(done.outcome.success);
                *se += done.joint_se.iter().sum::<f64>();
                *values += done.joint_steps * done.joint_se.len();
            }
        }
    }
    let rmse = |(_, se, values): &([usize; 2], f64, usize)| (se / *values as f64).sqrt();
    let ([grasps, pushes], [plain_grasps, plain_pushes]) = (tally[0].0, tally[1].0);
    let (with_stage, alone) = (rmse(&tally[0]), rmse(&tally[1]));
    println!(
        "with the stage: joint RMSE {with_stage:.4}, {pushes} pushes, {grasps} grasps of 40; \
         the network alone: {alone:.4}, {plain_pushes} pushes, {plain_grasps} grasps"
    );
    assert!(
        with_stage <= 0.85 * alone,
        "joint RMSE {with_stage} with the stage, {alone} without"
    );
    assert!(
        pushes > plain_pushes,
        "pushes landed: {pushes} with the stage, {plain_pushes} without"
    );
    assert!(
        grasps >= plain_grasps,
        "grasps carried: {grasps} with the stage, {plain_grasps} without"
    );
}

#[test]
fn train_joint_stage_adds_a_stage_to_a_model_file() {
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
            "--joint-stage",
            "--joint-stage-steps",
            "50",
            "--joint-stage-draws",
            "1",
            "--joint-stage-width",
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
        stderr.contains("fitting the joint stage: 6 training and 2 validation"),
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
    // Nothing to read; the stage's old name still works on the command line.
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
    assert!(stderr.contains("joint_stage_draws"), "{stderr}");
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
        stderr.contains("joint stage") && stderr.contains("blend below 1"),
        "{stderr}"
    );
    assert!(!tmp.path().join("out.dmbn").exists());
}
