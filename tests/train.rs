//! Training: the loss falls on a tiny generated dataset, `resume` reproduces the uninterrupted
//! run exactly, a non-finite loss stops with a clear error and keeps the last checkpoint, and
//! bad settings are refused.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::path::Path;
use std::sync::Mutex;

use dmbn::model::ModelKind;
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};
use dmbn::train::{Checkpoint, Metrics, TrainConfig, TrainError, Trainer};

/// A dataset of `n` ids × both actions from the simulator.
fn dataset(dir: &Path, n: u32) {
    support::simulated_dataset(dir, 0..n, &Action::ALL, 500);
}

fn small(model: ModelKind, steps: u64) -> TrainConfig {
    let mut c = TrainConfig::new(model, steps, 3);
    c.batch = 2;
    c.targets_per_sequence = 2;
    c.max_contexts = 3;
    c.val_batches = 1;
    c.val_every = 2;
    c.checkpoint_every = 2;
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
    static TURN: Mutex<()> = Mutex::new(());
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    Trainer::new(data, out, config)
}

#[test]
fn loss_falls_when_overfitting_a_tiny_dataset() {
    loss_falls(&ModelKind::ALL);
}

fn loss_falls(models: &[ModelKind]) {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 1);
    for &model in models {
        let out = tmp.path().join(model.name());
        let mut config = small(model, 30);
        config.lr = 3e-4;
        config.val_fraction = 0.0;
        config.val_every = 30;
        config.checkpoint_every = 30;
        let mut trainer = new_trainer(&data, &out, config).unwrap();
        let path = trainer.run(false, |_| {}).unwrap();
        assert!(path.exists());
        let m = metrics(&out);
        assert_eq!(m.len(), 30);
        let mean =
            |s: &[Metrics], f: fn(&Metrics) -> f32| s.iter().map(f).sum::<f32>() / s.len() as f32;
        let (first, last) = (mean(&m[..5], |x| x.loss), mean(&m[25..], |x| x.loss));
        assert!(last < first - 0.05, "{model}: loss {first} -> {last}");
        // Not only σ shrinking: the predicted frames get closer to the targets.
        let (first, last) = (
            mean(&m[..5], |x| x.image_mse),
            mean(&m[25..], |x| x.image_mse),
        );
        assert!(last < 0.95 * first, "{model}: image MSE {first} -> {last}");
    }
}

#[test]
fn resume_reproduces_the_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    dataset(&data, 3);
    let whole = tmp.path().join("whole");
    new_trainer(&data, &whole, small(ModelKind::Pte, 6))
        .unwrap()
        .run(false, |_| {})
        .unwrap();

    let parts = tmp.path().join("parts");
    new_trainer(&data, &parts, small(ModelKind::Pte, 4))
        .unwrap()
        .run(false, |_| {})
        .unwrap();
    let mut resumed = Trainer::resume(None, &parts, Some(6)).unwrap();
    assert_eq!(resumed.step_count(), 4);
    resumed.run(false, |_| {}).unwrap();

    let (a, b) = (metrics(&whole), metrics(&parts));
    assert_eq!(a.len(), 6);
    assert_eq!(b.len(), 6, "the resumed log reads as one run");
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(
            (x.step, x.loss, x.val_loss),
            (y.step, y.loss, y.val_loss),
            "step {}",
            x.step
        );
    }
    // Same final weights: identical predictions (the files may differ in parameter ids).
    let seq = episode(Action::Grasp, 9, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[0, 30]).unwrap();
    let predict = |dir: &Path| {
        Predictor::load(dir.join("model.dmbn"))
            .unwrap()
            .predict(&observations, &seq.times(), 0.5)
            .unwrap()
    };
    assert_eq!(predict(&whole), predict(&parts), "same final weights");
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
    trainer.run(false, |_| {}).unwrap();
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
    let best_model = Predictor::load(trainer.best_path()).unwrap();
    let last = Predictor::load(out.join("model.dmbn")).unwrap();
    let seq = episode(Action::Grasp, 9, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[0, 30]).unwrap();
    let predict = |p: &Predictor| p.predict(&observations, &seq.times(), 0.5).unwrap();
    assert_eq!(predict(&best_model) == predict(&last), best.0 == 6);
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
    let err = trainer.run(false, |_| {}).unwrap_err();
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
    let seq = episode(Action::Move, 9, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[10, 50]).unwrap();
    for (model, moves) in [(ModelKind::Attn, true), (ModelKind::Dmbn, false)] {
        let run = |weight: f64| {
            let out = tmp.path().join(format!("{}-{weight}", model.name()));
            let mut config = small(model, 2);
            config.drawn_frame_weight = weight;
            new_trainer(&data, &out, config)
                .unwrap()
                .run(false, |_| {})
                .unwrap();
            Predictor::load(out.join("model.dmbn"))
                .unwrap()
                .predict(&observations, &seq.times(), 0.5)
                .unwrap()
        };
        let (without, with) = (run(0.0), run(50.0));
        // Only the attentive model draws a frame of its own for the term to train.
        assert_eq!(without != with, moves, "{}", model.name());
    }
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
    config.image_size = 100;
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
    let err = new_trainer(&tmp.path().join("missing"), &out, small(ModelKind::Dmbn, 5))
        .err()
        .unwrap();
    assert!(err.to_string().contains("missing"), "{err}");
    let err = Trainer::resume(Some(&data), &tmp.path().join("nothing"), None)
        .err()
        .unwrap();
    assert!(err.to_string().contains("no checkpoint"), "{err}");
}
