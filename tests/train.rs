//! Training: the loss falls on a tiny generated dataset, `resume` reproduces the uninterrupted
//! run exactly (a finished run extended, and a cosine-schedule run killed between checkpoints),
//! the frame cache's size changes no step, frames gone bad mid-run stop it with an error
//! naming them, a non-finite loss stops with a clear error and keeps the last checkpoint, a
//! batch split between devices (`--devices cpu,cpu`) takes the single device's steps, and bad
//! settings are refused.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Mutex;

use dmbn::data::JointScale;
use dmbn::model::{read_header, ModelConfig, ModelKind, WeightDType};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};
use dmbn::train::{
    Checkpoint, Metrics, Schedule, TrainConfig, TrainDevice, TrainDevices, TrainError, Trainer,
};

/// A dataset of `n` ids × both actions from the simulator.
fn dataset(dir: &Path, n: u32) {
    support::simulated_dataset(dir, 0..n, &Action::ALL, 500);
}

fn small(model: ModelKind, steps: u64) -> TrainConfig {
    let mut c = TrainConfig::new(ModelConfig::new(model), steps, 3);
    c.batch = 2;
    c.targets_per_sequence = 2;
    c.max_contexts = 3;
    c.val_batches = 1;
    c.val_every = 2;
    c.checkpoint_every = 2;
    c.quality_sequences = 0;
    c
}

fn metrics(out: &Path) -> Vec<Metrics> {
    std::fs::read_to_string(out.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Trainers seed burn's generator, which the tests running beside each other share: they are
/// built one at a time, so each run's weights come from its seed alone.
fn new_trainer(data: &Path, out: &Path, config: TrainConfig) -> Result<Trainer, TrainError> {
    new_trainer_on("cpu", data, out, config)
}

/// [`new_trainer`] on `devices` (`train --devices`).
fn new_trainer_on(
    devices: &str,
    data: &Path,
    out: &Path,
    config: TrainConfig,
) -> Result<Trainer, TrainError> {
    static TURN: Mutex<()> = Mutex::new(());
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    Trainer::new_on(&devices.parse().unwrap(), data, out, config)
}

#[test]
fn loss_falls_when_overfitting_a_tiny_dataset() {
    loss_falls(&ModelKind::ALL);
}

fn loss_falls(models: &[ModelKind]) {
    // Steps enough for every network to start drawing its frames: on the pair the simulator
    // makes since its friction fix DMBN had not started by step 30 (image MSE 0.168 -> 0.167)
    // and had by 60 (0.115), measured.
    const STEPS: u64 = 60;
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    for &model in models {
        let out = tmp.path().join(model.name());
        let mut config = small(model, STEPS);
        config.lr = 3e-4;
        config.val_fraction = 0.0;
        config.val_every = STEPS;
        config.checkpoint_every = STEPS;
        let mut trainer = new_trainer(&data, &out, config).unwrap();
        let path = trainer.run(|_| {}).unwrap();
        assert!(path.exists());
        let m = metrics(&out);
        assert_eq!(m.len(), STEPS as usize);
        let mean =
            |s: &[Metrics], f: fn(&Metrics) -> f32| s.iter().map(f).sum::<f32>() / s.len() as f32;
        let (first, last) = (
            mean(&m[..5], |x| x.loss),
            mean(&m[STEPS as usize - 5..], |x| x.loss),
        );
        assert!(last < first - 0.05, "{model}: loss {first} -> {last}");
        // Not only σ shrinking: the predicted frames get closer to the targets.
        let (first, last) = (
            mean(&m[..5], |x| x.image_mse),
            mean(&m[STEPS as usize - 5..], |x| x.image_mse),
        );
        assert!(last < 0.95 * first, "{model}: image MSE {first} -> {last}");
    }
}

/// A run of `config` into `out`, to its last step.
fn run_to_the_end(data: &Path, out: &Path, config: TrainConfig) {
    new_trainer(data, out, config).unwrap().run(|_| {}).unwrap();
}

/// A run of `config` into `out` killed (a panic in its progress callback) right after step
/// `step` was logged: what a crash leaves behind.
fn run_killed_after(data: &Path, out: &Path, config: TrainConfig, step: u64) {
    let mut trainer = new_trainer(data, out, config).unwrap();
    let killed = catch_unwind(AssertUnwindSafe(|| {
        trainer.run(|p| {
            if p.step == step {
                panic!("killed after step {step}");
            }
        })
    }));
    assert!(killed.is_err(), "the run was not interrupted");
}

/// A line of `metrics.jsonl` without its one wall-clock field: what two runs of the same
/// steps must agree on exactly.
fn deterministic(m: &Metrics) -> Metrics {
    Metrics {
        steps_per_s: 0.0,
        ..m.clone()
    }
}

/// The prediction of a fixed episode by the model file at `path`: equal predictions, equal
/// weights (the files may differ in parameter ids).
fn prediction(path: &Path) -> dmbn::predict::SequencePrediction {
    let seq = episode(Action::Grasp, 9, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[0, 30]).unwrap();
    Predictor::load(path)
        .unwrap()
        .predict(&observations, &seq.times(), 0.5)
        .unwrap()
}

/// The final model's prediction (see [`prediction`]).
fn final_prediction(out: &Path) -> dmbn::predict::SequencePrediction {
    prediction(&out.join("model.dmbn"))
}

#[test]
fn resume_reproduces_the_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let whole = tmp.path().join("whole");
    new_trainer(&data, &whole, small(ModelKind::Pte, 6))
        .unwrap()
        .run(|_| {})
        .unwrap();

    let parts = tmp.path().join("parts");
    new_trainer(&data, &parts, small(ModelKind::Pte, 4))
        .unwrap()
        .run(|_| {})
        .unwrap();
    let mut resumed = Trainer::resume(None, &parts, Some(6)).unwrap();
    assert_eq!(resumed.step_count(), 4);
    resumed.run(|_| {}).unwrap();

    let (a, b) = (metrics(&whole), metrics(&parts));
    assert_eq!(a.len(), 6);
    assert_eq!(b.len(), 6, "the resumed log reads as one run");
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(deterministic(x), deterministic(y), "step {}", x.step);
    }
    assert_eq!(
        final_prediction(&whole),
        final_prediction(&parts),
        "same final weights"
    );
}

#[test]
fn the_frame_cache_s_size_changes_no_step() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let run = |mib: usize| {
        let out = tmp.path().join(format!("cache-{mib}"));
        let mut config = small(ModelKind::Pte, 4);
        config.frame_cache_mib = mib;
        run_to_the_end(&data, &out, config);
        out
    };
    // None kept (every frame decoded when drawn), and the whole dataset kept.
    let (none, all) = (run(0), run(64));
    for (x, y) in metrics(&none).iter().zip(&metrics(&all)) {
        assert_eq!(deterministic(x), deterministic(y), "step {}", x.step);
    }
    assert_eq!(final_prediction(&none), final_prediction(&all));
}

#[test]
fn frames_gone_bad_mid_run_stop_it_with_an_error_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 2);
    let mut config = small(ModelKind::Pte, 20);
    config.frame_cache_mib = 0;
    let mut trainer = new_trainer(&data, &tmp.path().join("run"), config).unwrap();
    trainer.step().unwrap();
    for id in ["0", "1"] {
        for action in Action::ALL {
            let dir = data.join(id).join(action.name());
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "png") {
                    std::fs::write(&path, b"not a png").unwrap();
                }
            }
        }
    }
    // The batches read ahead before the damage, then the error (not a panic, not a wait).
    let error = (0..4)
        .find_map(|_| trainer.step().err())
        .expect("the damaged frames are noticed");
    let message = error.to_string();
    assert!(
        message.starts_with(&data.display().to_string())
            && message.contains(".png: cannot decode frame"),
        "{message}"
    );
    assert!(
        matches!(trainer.step(), Err(TrainError::Batches { .. })),
        "and no batch after it"
    );
}

#[test]
fn a_cosine_run_killed_between_checkpoints_resumes_as_if_never_stopped() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let (steps, killed_at) = (7, 5);
    let mut config = small(ModelKind::Pte, steps);
    config.lr = 1e-3;
    config.schedule = Schedule::Cosine {
        final_fraction: 0.1,
    };
    config.checkpoint_every = 3;
    config.half = true;
    let whole = tmp.path().join("whole");
    run_to_the_end(&data, &whole, config.clone());

    // Killed right after step 5 was logged: the last checkpoint is step 3's, and the log
    // holds steps 4 and 5 that the resumed run must redo (and not log twice).
    let parts = tmp.path().join("parts");
    run_killed_after(&data, &parts, config.clone(), killed_at);
    assert!(
        !parts.join("model.dmbn").exists(),
        "the killed run never finished"
    );
    assert_eq!(Checkpoint::read(&parts).unwrap().2.step, 3);
    assert_eq!(metrics(&parts).len(), killed_at as usize);

    let mut resumed = Trainer::resume(None, &parts, None).unwrap();
    assert_eq!(resumed.step_count(), 3, "from the last checkpoint");
    // The run's settings, with the joint count it read from the data.
    let mut settings = config.clone();
    settings.model.joints = Some(dmbn::data::JOINTS);
    assert_eq!(resumed.config(), &settings, "with the run's own settings");
    assert_eq!(
        resumed.data(),
        Some(std::path::absolute(&data).unwrap().as_path())
    );
    resumed.run(|_| {}).unwrap();
    let written = std::fs::read(parts.join("model.dmbn")).unwrap();
    assert_eq!(
        read_header(&written).unwrap().weights.dtype,
        WeightDType::F16,
        "the resumed run writes f16 weights, as the run asked"
    );

    let (a, b) = (metrics(&whole), metrics(&parts));
    assert_eq!(a.len(), steps as usize);
    assert_eq!(
        b.iter().map(|m| m.step).collect::<Vec<_>>(),
        (1..=steps).collect::<Vec<_>>(),
        "the resumed log reads as one run"
    );
    for (x, y) in a.iter().zip(&b) {
        // Losses, learning rate, validation: everything but the speed.
        assert_eq!(deterministic(x), deterministic(y), "step {}", x.step);
    }
    // The learning rates are the cosine of the whole run (a resumed schedule restarted, or
    // stretched over the remaining steps, would differ), falling at every step.
    for m in &a {
        // (Within an ulp: metrics.jsonl is read back by serde_json, whose float parsing may
        // round the last bit differently.)
        let want = config.schedule.rate(config.lr, m.step - 1, steps);
        assert!(
            (m.lr - want).abs() <= 1e-15 * want,
            "step {}: {} vs {want}",
            m.step,
            m.lr
        );
    }
    assert!(a.windows(2).all(|w| w[1].lr < w[0].lr), "{a:?}");
    assert_eq!(a[0].lr, config.lr, "the cosine starts at the base rate");
    let last = a.last().unwrap().lr;
    assert!(
        (last - 0.1 * config.lr).abs() < 1e-12,
        "and ends at 10% of it: {last}"
    );
    assert!(a.iter().any(|m| m.val_loss.is_some()));
    assert_eq!(
        final_prediction(&whole),
        final_prediction(&parts),
        "same final weights"
    );
    let (state_a, state_b) = (
        Checkpoint::read(&whole).unwrap().2,
        Checkpoint::read(&parts).unwrap().2,
    );
    assert_eq!(state_a.step, steps);
    assert_eq!(
        (state_a.step, state_a.best_val, &state_a.rng),
        (state_b.step, state_b.best_val, &state_b.rng),
        "same final checkpoint state"
    );
}

#[test]
fn the_quality_benchmark_keeps_the_best_model_on_held_out_sequences() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 4);
    let out = tmp.path().join("out");
    let mut config = small(ModelKind::Attn, 6);
    config.quality_sequences = 2;
    config.prefix_contexts = 0.5;
    let mut trainer = new_trainer(&data, &out, config).unwrap();
    trainer.run(|_| {}).unwrap();
    let m = metrics(&out);
    let scores: Vec<(u64, f32)> = m
        .iter()
        .filter_map(|x| x.val_quality.map(|q| (x.step, q.score())))
        .collect();
    assert_eq!(
        scores.iter().map(|s| s.0).collect::<Vec<_>>(),
        [2, 4, 6],
        "scored at each validation"
    );
    for q in m.iter().filter_map(|x| x.val_quality) {
        let ratios = [
            q.interp_joint,
            q.interp_image,
            q.extrap_joint,
            q.extrap_image,
        ];
        assert!(ratios.iter().all(|r| r.is_finite() && *r > 0.0), "{q:?}");
    }
    let best = scores
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert_eq!(trainer.best_quality(), Some(best));
    // best.dmbn is the model of that step: at the last step it is the final model too.
    assert_eq!(
        prediction(&trainer.best_path()) == final_prediction(&out),
        best.0 == 6
    );
    let (_, _, state) = Checkpoint::read(&out).unwrap();
    assert_eq!(
        state.best_quality,
        Some(best),
        "the checkpoint keeps it for --resume"
    );
}

#[test]
fn non_finite_loss_stops_and_keeps_the_last_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 2);
    let out = tmp.path().join("out");
    let mut config = small(ModelKind::Dmbn, 50);
    config.lr = 1e30;
    config.clip_norm = 1e30;
    config.checkpoint_every = 1;
    let mut trainer = new_trainer(&data, &out, config).unwrap();
    let err = trainer.run(|_| {}).unwrap_err();
    let TrainError::NonFinite { step, .. } = err else {
        panic!("expected a non-finite loss, got {err}")
    };
    assert!(err.to_string().contains("last good checkpoint"), "{err}");
    let (_, _, state) = Checkpoint::read(&out).unwrap();
    assert_eq!(
        state.step,
        step - 1,
        "the checkpoint is the last finite step"
    );
    assert!(!out.join("model.dmbn").exists());
}

#[test]
fn the_drawn_frame_weight_trains_the_attentive_model_s_own_frame_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    for (model, moves) in [(ModelKind::Attn, true), (ModelKind::Dmbn, false)] {
        let run = |weight: f64| {
            let out = tmp.path().join(format!("{}-{weight}", model.name()));
            let mut config = small(model, 2);
            config.drawn_frame_weight = weight;
            new_trainer(&data, &out, config)
                .unwrap()
                .run(|_| {})
                .unwrap();
            final_prediction(&out)
        };
        let (without, with) = (run(0.0), run(50.0));
        // Only the attentive model draws a frame of its own for the term to train.
        assert_eq!(without != with, moves, "{}", model.name());
    }
}

#[test]
fn beta_nll_changes_the_training_and_not_the_reported_nll_s_definition() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    let run = |beta: f64| {
        let out = tmp.path().join(format!("pte-{beta}"));
        let mut config = small(ModelKind::Pte, 2);
        config.beta_nll = beta;
        let mut trainer = new_trainer(&data, &out, config).unwrap();
        // The first step's loss parts come from the same weights and batch either way.
        let (first, _) = trainer.step().unwrap();
        trainer.run(|_| {}).unwrap();
        (first, final_prediction(&out))
    };
    let ((plain, without), (weighted, with)) = (run(0.0), run(1.0));
    assert_eq!(plain.image_nll, weighted.image_nll);
    assert_eq!(plain.joint_nll, weighted.joint_nll);
    // σ < 1, so the σ²-weighted total is the smaller, and the weights move differently.
    assert!(weighted.total < plain.total, "{weighted:?} vs {plain:?}");
    assert!(without != with);
}

#[test]
fn bad_settings_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    let out = tmp.path().join("out");
    let mut config = small(ModelKind::Dmbn, 5);
    config.batch = 0;
    let err = new_trainer(&data, &out, config).err().unwrap();
    assert!(err.to_string().contains("batch"), "{err}");
    let mut config = small(ModelKind::Dmbn, 5);
    config.val_batches = 0;
    let err = new_trainer(&data, &out, config).err().unwrap();
    assert!(err.to_string().contains("val_batches"), "{err}");
    let mut config = small(ModelKind::Dmbn, 5);
    config.model.image_size = 100;
    assert!(new_trainer(&data, &out, config).is_err());
    let mut config = small(ModelKind::Attn, 5);
    config.single_modality = 1.5;
    let err = new_trainer(&data, &out, config).err().unwrap();
    assert!(err.to_string().contains("single_modality"), "{err}");
    let mut config = small(ModelKind::Attn, 5);
    config.prefix_contexts = -0.1;
    let err = new_trainer(&data, &out, config).err().unwrap();
    assert!(err.to_string().contains("prefix_contexts"), "{err}");
    let mut config = small(ModelKind::Attn, 5);
    config.drawn_frame_weight = f64::NAN;
    let err = new_trainer(&data, &out, config).err().unwrap();
    assert!(err.to_string().contains("drawn_frame_weight"), "{err}");
    for beta in [-0.5, 1.5, f64::NAN] {
        let mut config = small(ModelKind::Pte, 5);
        config.beta_nll = beta;
        let err = new_trainer(&data, &out, config).err().unwrap();
        assert!(err.to_string().contains("beta_nll"), "{beta}: {err}");
    }
    let err = new_trainer(&tmp.path().join("missing"), &out, small(ModelKind::Dmbn, 5))
        .err()
        .unwrap();
    assert!(err.to_string().contains("missing"), "{err}");
    let err = Trainer::resume(Some(&data), &tmp.path().join("nothing"), None)
        .err()
        .unwrap();
    assert!(err.to_string().contains("no checkpoint"), "{err}");
}

#[test]
fn init_starts_from_a_model_files_weights_with_the_runs_normalisation() {
    let tmp = tempfile::tempdir().unwrap();
    let (data, other) = (tmp.path().join("data"), tmp.path().join("other"));
    dataset(&data, 2);
    // Other episodes: another joint normalisation than the file's.
    support::simulated_dataset(&other, 0..2, &Action::ALL, 900);
    let first = tmp.path().join("first");
    new_trainer(&data, &first, small(ModelKind::Pte, 2))
        .unwrap()
        .run(|_| {})
        .unwrap();
    let run = |on: &Path, init: Option<&Path>, name: &str| {
        let mut config = small(ModelKind::Pte, 1);
        // (A step this small leaves the weights as they start.)
        config.lr = 1e-12;
        config.init = init.map(Path::to_path_buf);
        let out = tmp.path().join(name);
        new_trainer(on, &out, config).unwrap().run(|_| {}).unwrap();
        out
    };
    let normalization = |out: &Path| {
        let bytes = std::fs::read(out.join("model.dmbn")).unwrap();
        read_header(&bytes).unwrap().normalization
    };
    let before = final_prediction(&first);
    let largest = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max)
    };
    let init = first.join("model.dmbn");
    // On the file's own data: the file's model, normalisation included.
    let continued = run(&data, Some(&init), "continued");
    assert_eq!(normalization(&continued), normalization(&first));
    let after = final_prediction(&continued);
    assert!(largest(&before.image_mean, &after.image_mean) < 1e-4);
    assert!(largest(&before.joint_mean, &after.joint_mean) < 1e-4);
    // On other data: the data's normalisation (as a fresh run's, not the file's), the file's
    // weights (not a fresh run's).
    let tuned = run(&other, Some(&init), "tuned");
    let fresh = run(&other, None, "fresh");
    assert_ne!(normalization(&tuned), normalization(&first));
    assert_eq!(normalization(&tuned), normalization(&fresh));
    let (tuned, fresh) = (final_prediction(&tuned), final_prediction(&fresh));
    assert!(largest(&tuned.image_mean, &fresh.image_mean) > 1e-3);
    assert!(largest(&before.joint_mean, &tuned.joint_mean) > 1e-3);
    // A file of another kind is refused, naming the setting.
    let mut wrong = small(ModelKind::Dmbn, 1);
    wrong.init = Some(first.join("model.dmbn"));
    match new_trainer(&other, &tmp.path().join("wrong"), wrong) {
        Err(TrainError::Config {
            field: "init",
            message,
        }) => {
            assert!(message.contains("model.dmbn"), "{message}")
        }
        other => panic!("expected an init error, got {:?}", other.err()),
    }
}

#[test]
fn a_shared_joint_scale_divides_the_arm_by_one_scale_and_trains_in_those_units() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 2);
    let run = |scale: JointScale, name: &str| {
        let mut config = small(ModelKind::Pte, 2);
        config.joint_scale = scale;
        let out = tmp.path().join(name);
        new_trainer(&data, &out, config)
            .unwrap()
            .run(|_| {})
            .unwrap();
        let bytes = std::fs::read(out.join("model.dmbn")).unwrap();
        (read_header(&bytes).unwrap().normalization, metrics(&out))
    };
    let (per_joint, per_joint_metrics) = run(JointScale::PerJoint, "per-joint");
    let (shared, shared_metrics) = run(JointScale::Shared, "shared");
    let arm = &per_joint.std[..6];
    let rms = (arm.iter().map(|s| s * s).sum::<f32>() / 6.0).sqrt();
    assert!(arm.iter().any(|s| (s - rms).abs() > 1e-3), "{arm:?}");
    for j in 0..6 {
        assert!((shared.std[j] - rms).abs() < 1e-6, "{j}: {shared:?}");
    }
    assert_eq!(
        shared.std[6], per_joint.std[6],
        "the gripper keeps its scale"
    );
    assert_eq!(shared.mean, per_joint.mean);
    // The joints are fed and judged in other units: other losses from the first step.
    assert_ne!(shared_metrics[0].joint_mse, per_joint_metrics[0].joint_mse);
}

#[test]
fn schedules_start_and_end_where_they_say() {
    let (lr, steps) = (1e-3, 9);
    let rates = |s: Schedule| -> Vec<f64> { (0..steps).map(|k| s.rate(lr, k, steps)).collect() };
    assert!(rates(Schedule::Constant).iter().all(|&r| r == lr));
    let cosine = rates(Schedule::Cosine {
        final_fraction: 0.05,
    });
    assert_eq!(cosine[0], lr);
    assert!((cosine[8] - 0.05 * lr).abs() < 1e-15, "{cosine:?}");
    assert!(
        (cosine[4] - 0.525 * lr).abs() < 1e-15,
        "halfway, half-way down: {cosine:?}"
    );
    assert!(cosine.windows(2).all(|w| w[1] < w[0]));
    // `train --schedule step`: every steps/3, gamma 0.3.
    let step = rates(Schedule::Step {
        every: 3,
        gamma: 0.3,
    });
    let want = [1.0, 1.0, 1.0, 0.3, 0.3, 0.3, 0.09, 0.09, 0.09].map(|f| f * lr);
    for (got, want) in step.iter().zip(want) {
        assert!((got - want).abs() < 1e-15, "{step:?}");
    }
    // A one-step run stays at the base rate (no division by zero).
    let one = Schedule::Cosine {
        final_fraction: 0.05,
    };
    assert_eq!(one.rate(lr, 0, 1), lr);
}

#[test]
fn val_fraction_0_holds_no_id_out_and_the_trainer_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let mut config = small(ModelKind::Pte, 1);
    config.val_fraction = 0.0;
    let trainer = new_trainer(&data, &tmp.path().join("a"), config.clone()).unwrap();
    assert_eq!(trainer.val_ids(), &[] as &[u32]);
    assert!(trainer.validates_on_training_data());
    config.val_fraction = 0.1;
    let trainer = new_trainer(&data, &tmp.path().join("b"), config).unwrap();
    assert_eq!(
        trainer.val_ids(),
        &[2],
        "a fraction above 0 holds at least one id out"
    );
    assert!(!trainer.validates_on_training_data());
    // The command line says it before training.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_train"))
        .args([
            "--model",
            "pte",
            "--steps",
            "1",
            "--batch",
            "1",
            "--val-fraction",
            "0",
        ])
        .args(["--quality-sequences", "0", "--data"])
        .arg(&data)
        .arg("--out")
        .arg(tmp.path().join("c"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("no id is held out"), "{stderr}");
    assert!(
        stderr.contains("measured on training sequences"),
        "{stderr}"
    );
}

#[test]
fn a_crash_between_the_checkpoints_renames_resumes_from_the_previous_one() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let config = small(ModelKind::Dmbn, 4);
    let whole = tmp.path().join("whole");
    run_to_the_end(&data, &whole, config.clone());

    // Killed while writing step 4's checkpoint, after `checkpoint/` became `checkpoint.old/`
    // and before `checkpoint.tmp/` became `checkpoint/`: the complete step-2 checkpoint is
    // the old one, and the new one lies half-written.
    let parts = tmp.path().join("parts");
    run_killed_after(&data, &parts, config.clone(), 3);
    let (dir, old, tmp_dir) = (
        Checkpoint::dir(&parts),
        parts.join("checkpoint.old"),
        parts.join("checkpoint.tmp"),
    );
    std::fs::rename(&dir, &old).unwrap();
    std::fs::create_dir_all(&tmp_dir).unwrap();
    std::fs::write(tmp_dir.join("model.dmbn"), b"half a file").unwrap();
    assert_eq!(
        Checkpoint::read(&parts).unwrap().2.step,
        2,
        "the old checkpoint is read"
    );

    let mut resumed = Trainer::resume(None, &parts, None).unwrap();
    assert_eq!(resumed.step_count(), 2);
    resumed.run(|_| {}).unwrap();
    assert_eq!(
        final_prediction(&whole),
        final_prediction(&parts),
        "same final weights"
    );
    assert_eq!(Checkpoint::read(&parts).unwrap().2.step, 4);
    assert!(
        !old.exists() && !tmp_dir.exists(),
        "the next checkpoint cleans both up"
    );
}

#[test]
fn augmented_training_warps_its_batches_and_resumes_exactly() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let plain = small(ModelKind::Pte, 4);
    let mut warped = plain.clone();
    warped.augment = Some(dmbn::augment::TimeWarpConfig {
        probability: 1.0,
        freeze_probability: 1.0,
        ..Default::default()
    });
    let run = |config: &TrainConfig, name: &str| {
        let out = tmp.path().join(name);
        run_to_the_end(&data, &out, config.clone());
        out
    };
    let (a, b) = (run(&plain, "plain"), run(&warped, "warped"));
    let (ma, mb) = (metrics(&a), metrics(&b));
    assert_ne!(
        ma[0].loss, mb[0].loss,
        "the same seed trains on other (warped) batches"
    );
    assert!(mb.iter().all(|m| m.loss.is_finite()));

    // Killed after step 3, resumed from step 2's checkpoint: the warps drawn are the same.
    let parts = tmp.path().join("parts");
    run_killed_after(&data, &parts, warped.clone(), 3);
    let mut resumed = Trainer::resume(None, &parts, None).unwrap();
    assert_eq!(resumed.config().augment, warped.augment);
    resumed.run(|_| {}).unwrap();
    let mp = metrics(&parts);
    for (x, y) in mb.iter().zip(&mp) {
        assert_eq!(deterministic(x), deterministic(y), "step {}", x.step);
    }
    assert_eq!(final_prediction(&b), final_prediction(&parts));
}

#[test]
fn devices_are_parsed_and_a_backend_not_built_says_how_to_build_it() {
    for bad in ["gpu", "wgpu:x", "cpu:1", ""] {
        let err = bad.parse::<TrainDevice>().unwrap_err();
        assert!(
            err.contains("expected cpu, wgpu") || err.contains("must be a number"),
            "{bad:?}: {err}"
        );
    }
    assert_eq!(
        "wgpu:1".parse::<TrainDevice>(),
        Ok(TrainDevice::Wgpu(Some(1)))
    );
    assert_eq!("cuda".parse::<TrainDevice>(), Ok(TrainDevice::Cuda(0)));
    assert_eq!("cpu".parse::<TrainDevice>(), Ok(TrainDevice::Cpu));
    for device in [
        TrainDevice::Wgpu(None),
        TrainDevice::Cpu,
        TrainDevice::Cuda(2),
    ] {
        assert_eq!(device.to_string().parse::<TrainDevice>(), Ok(device));
    }
    #[cfg(not(feature = "cuda"))]
    {
        let err = TrainDevice::Cuda(0).device().err().unwrap().to_string();
        assert!(err.contains("--features cuda"), "{err}");
    }
    #[cfg(not(feature = "wgpu"))]
    {
        let err = TrainDevice::Wgpu(None).device().err().unwrap().to_string();
        assert!(err.contains("--features wgpu"), "{err}");
    }
}

#[test]
fn glorot_initialization_draws_the_original_keras_weights_and_trains_them() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    let run = |initialization, lr, name: &str| {
        let mut config = small(ModelKind::Dmbn, 2);
        config.val_fraction = 0.0;
        config.initialization = initialization;
        config.lr = lr;
        let out = tmp.path().join(name);
        run_to_the_end(&data, &out, config);
        let file = std::fs::read(out.join("model.dmbn")).unwrap();
        // The exported (PyTorch-named) tensors.
        support::safetensors_values(&dmbn::model::export_safetensors(&file, false).unwrap())
    };
    use dmbn::model::Initialization::{Glorot, He};
    // A learning rate too small to move anything: the weights as drawn.
    let (glorot, he) = (run(Glorot, 1e-30, "glorot"), run(He, 1e-30, "he"));
    // Glorot-uniform: U(±√(6 / (fan-in + fan-out))), receptive fields in both fans.
    for (name, fan_in, fan_out) in [
        ("decoder.shared.weight", 129, 1024),
        ("image_encoder.convs.0.weight", 4 * 9, 32 * 9),
        ("joint_encoder.layers.0.weight", 8, 32),
    ] {
        let limit = (6.0f32 / (fan_in + fan_out) as f32).sqrt();
        let w = &glorot[name];
        let largest = w.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        assert!(
            largest <= limit && largest > 0.9 * limit,
            "{name}: {largest} vs {limit}"
        );
        let std = (w.iter().map(|v| v * v).sum::<f32>() / w.len() as f32).sqrt();
        let want = limit / 3f32.sqrt();
        assert!(
            (std / want - 1.0).abs() < 0.1,
            "{name}: std {std}, uniform's {want}"
        );
        // He-uniform's range, sqrt(6 / fan-in), is wider.
        let he_largest = he[name].iter().fold(0.0f32, |m, v| m.max(v.abs()));
        assert!(
            he_largest > 1.3 * largest,
            "{name}: he {he_largest}, glorot {largest}"
        );
    }
    // Zero biases (moved by at most the 1e-30 step).
    assert!(glorot["decoder.shared.bias"]
        .iter()
        .all(|b| b.abs() < 1e-20));
    // The redrawn weights train (a fresh tensor does not track gradients by itself).
    let trained = run(Glorot, 1e-3, "trained");
    for name in ["decoder.shared.weight", "image_encoder.convs.0.weight"] {
        assert_ne!(trained[name], glorot[name], "{name} did not train");
    }
    // Refused for the attentive model (its gates and read-out start from zero by design).
    let mut config = small(ModelKind::Attn, 2);
    config.initialization = Glorot;
    let err = new_trainer(&data, &tmp.path().join("attn"), config)
        .err()
        .unwrap();
    assert!(err.to_string().contains("initialization"), "{err}");
}

/// Relative tolerance of a data-parallel run's losses and weights against one device's: the
/// same sums in another order (the shards' gradients are added after the backward pass), so
/// f32 rounding only (under 4e-7 here; leaving out the 1/N on the shards' losses moves them
/// by 4e-4 within 4 steps).
const SPLIT_TOLERANCE: f32 = 1e-5;

/// `a` and `b` within [`SPLIT_TOLERANCE`] of the larger of `|a|` and 1 (`what` in the message).
fn assert_close(a: f32, b: f32, what: &str) {
    assert!(
        (a - b).abs() <= SPLIT_TOLERANCE * a.abs().max(1.0),
        "{what}: one device {a}, split {b}"
    );
}

/// Every loss of each step's line, training and validation.
fn losses(m: &Metrics) -> Vec<(&'static str, Option<f32>)> {
    vec![
        ("loss", Some(m.loss)),
        ("image_nll", Some(m.image_nll)),
        ("joint_nll", Some(m.joint_nll)),
        ("image_mse", Some(m.image_mse)),
        ("joint_mse", Some(m.joint_mse)),
        ("val_loss", m.val_loss),
        ("val_context_loss", m.val_context_loss),
    ]
}

/// The final model's weights by (exported) name.
fn final_weights(out: &Path) -> std::collections::HashMap<String, Vec<f32>> {
    let file = std::fs::read(out.join("model.dmbn")).unwrap();
    support::safetensors_values(&dmbn::model::export_safetensors(&file, false).unwrap())
}

#[test]
fn a_batch_split_between_devices_takes_the_single_device_s_steps() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let mut config = small(ModelKind::Pte, 4);
    config.batch = 4;
    config.joint_targets = 2;
    let one = tmp.path().join("one");
    run_to_the_end(&data, &one, config.clone());
    let two = tmp.path().join("two");
    new_trainer_on("cpu,cpu", &data, &two, config.clone())
        .unwrap()
        .run(|_| {})
        .unwrap();
    // Half a run on one device, resumed on four (a checkpoint moves between device lists).
    let four = tmp.path().join("four");
    let mut half = config.clone();
    half.steps = 2;
    run_to_the_end(&data, &four, half);
    let mut resumed =
        Trainer::resume_on(&"cpu,cpu,cpu,cpu".parse().unwrap(), None, &four, Some(4)).unwrap();
    resumed.run(|_| {}).unwrap();

    let reference = metrics(&one);
    let expected = final_weights(&one);
    for split in [&two, &four] {
        let name = split.file_name().unwrap().to_string_lossy();
        let m = metrics(split);
        assert_eq!(m.len(), reference.len(), "{name}");
        for (a, b) in reference.iter().zip(&m) {
            assert_eq!(a.step, b.step);
            for ((what, x), (_, y)) in losses(a).into_iter().zip(losses(b)) {
                let what = format!("{name}, step {}, {what}", a.step);
                match (x, y) {
                    (Some(x), Some(y)) => assert_close(x, y, &what),
                    (x, y) => assert_eq!(x.is_some(), y.is_some(), "{what}"),
                }
            }
        }
        let weights = final_weights(split);
        assert_eq!(weights.len(), expected.len(), "{name}");
        for (tensor, want) in &expected {
            for (i, (x, y)) in want.iter().zip(&weights[tensor]).enumerate() {
                assert_close(*x, *y, &format!("{name}, {tensor}[{i}]"));
            }
        }
    }
}

#[test]
fn a_batch_that_does_not_split_evenly_and_bad_device_lists_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    let mut config = small(ModelKind::Pte, 2);
    config.batch = 3;
    let err = new_trainer_on("cpu,cpu", &data, &tmp.path().join("a"), config.clone())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("--batch 3") && err.contains("--devices cpu,cpu"),
        "{err}"
    );
    assert!(!tmp.path().join("a").exists(), "nothing written");
    // A checkpoint's batch too, when resumed on more devices.
    let out = tmp.path().join("b");
    run_to_the_end(&data, &out, config);
    let devices: TrainDevices = "cpu,cpu".parse().unwrap();
    let err = Trainer::resume_on(&devices, None, &out, Some(3))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("--batch 3"), "{err}");
    // The command line refuses bad lists, naming what is wrong, without panicking.
    for (devices, says) in [
        ("wgpu:x", "must be a number"),
        ("", "no device given"),
        ("cpu,", "device 2 is empty"),
        ("cpu,gpu", "expected cpu, wgpu"),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_train"))
            .args(["--model", "pte", "--steps", "1", "--batch", "2"])
            .args(["--devices", devices, "--data"])
            .arg(&data)
            .arg("--out")
            .arg(tmp.path().join("c"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{devices:?}: {stderr}");
        assert!(stderr.contains(says), "{devices:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{devices:?}: {stderr}");
    }
}
