//! The shipped weights behind docs/results.md: each file is the model its name says, small
//! enough to ship, and predicts sanely; with the original DMBN data present, the
//! original-data weights reconstruct its held-out sequences and use their observations (better
//! than an untrained model and than the action's mean motion; reported as skipped without
//! the data). Without it, they are checked on simulated episodes as far as the other scene
//! allows: their frames, not their joints (another arm), beat an untrained model's.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use dmbn::augment::{EvalMode, EvalSequence};
use dmbn::data::{Dataset, Sequence};
use dmbn::eval::{evaluate, evenly_spaced};
use dmbn::model::ModelKind;
use dmbn::predict::{Observations, Predictor};
use dmbn::quality::{MeanMotion, Scenario};
use dmbn::sim::{episode, Action};

/// Every shipped model file and what it must hold.
const SHIPPED: [(&str, ModelKind); 9] = [
    ("attn-sim", ModelKind::Attn),
    ("dmbn-sim", ModelKind::Dmbn),
    ("pte-sim", ModelKind::Pte),
    ("pte-aug-sim", ModelKind::Pte),
    ("attn-2020", ModelKind::Attn),
    ("dmbn-2020", ModelKind::Dmbn),
    ("pte-2020", ModelKind::Pte),
    ("pte-aug-2020", ModelKind::Pte),
    // The paper's DMBN with the original's recipe, for Table 1 (it hardly reads its joints).
    ("dmbn-paper-2020", ModelKind::Dmbn),
];

fn shipped(name: &str) -> Predictor {
    let path = support::asset(&format!("models/{name}.dmbn"));
    Predictor::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn shipped_weights_are_the_models_their_names_say() {
    let seq = episode(Action::Grasp, 11, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[0, 15, 30]).unwrap();
    for (name, kind) in SHIPPED {
        let bytes = std::fs::metadata(support::asset(&format!("models/{name}.dmbn")))
            .unwrap()
            .len();
        assert!(
            bytes < 10_000_000,
            "{name}: {bytes} bytes, expected < 10 MB"
        );
        let predictor = shipped(name);
        assert_eq!(predictor.model().kind(), kind, "{name}");
        assert_eq!(predictor.model().image_size(), 64, "{name}");
        let p = predictor.predict(&observations, &seq.times(), 0.5).unwrap();
        assert_eq!(p.len(), seq.len(), "{name}");
        for (what, values) in [
            ("image mean", &p.image_mean),
            ("image sigma", &p.image_sigma),
            ("joint mean", &p.joint_mean),
            ("joint sigma", &p.joint_sigma),
        ] {
            assert!(
                values.iter().all(|v| v.is_finite()),
                "{name}: non-finite {what}"
            );
        }
        assert!(
            p.image_mean.iter().all(|v| (0.0..=1.0).contains(v)),
            "{name}: pixel means outside [0, 1]"
        );
        // Joint σ is in the episode's units (scaled by each joint's spread), so only the
        // image σ is bounded by the floor itself.
        assert!(
            p.image_sigma.iter().all(|&s| s >= 0.0099),
            "{name}: an image σ below the floor 0.01"
        );
        assert!(
            p.joint_sigma.iter().all(|&s| s > 0.0),
            "{name}: a joint σ that is not positive"
        );
    }
}

/// Mean image and joint MSE of `model` over the unchanged held-out sequences `ids`, each with
/// 20 evenly spaced observations of both modalities.
fn mean_mse(model: &Predictor, data: &Dataset, ids: &[u32]) -> (f64, f64) {
    let (mut image, mut joint, mut n) = (0.0, 0.0, 0.0);
    for seq_ref in data.sequences().iter().filter(|s| ids.contains(&s.id)) {
        let seq = data.read(seq_ref, Some(64)).unwrap();
        let observed = evenly_spaced(seq.len(), 20);
        let shown = EvalSequence::unchanged(&seq);
        let e = evaluate(model, EvalMode::Unchanged, shown, observed, 0.5).unwrap();
        image += e.scores.image_mse;
        joint += e.scores.joint_mse;
        n += 1.0;
    }
    (image / n, joint / n)
}

/// The shipped original-data weights on held-out ids of the original data (the figures of
/// docs/results.md): each reconstructs the action with the image error it was shipped with,
/// and its joints better than the action-independent mean (MSE 1 in standardised units).
#[test]
fn original_data_weights_reconstruct_held_out_sequences() {
    let Some(data) = support::dmbn2020_dataset() else {
        return;
    };
    for name in ["dmbn-2020", "pte-2020", "pte-aug-2020"] {
        let (image, joint) = mean_mse(&shipped(name), &data, &[38, 39]);
        println!("{name}: image MSE {image:.4}, joint MSE {joint:.3}");
        assert!(image < 0.016, "{name}: image MSE {image}");
        assert!(joint < 0.9, "{name}: joint MSE {joint}");
    }
}

/// Every `-2020` file on the held-out ids 32-39 of the original data, 5 observations of both
/// modalities (`dmbn score`'s interp): the joints and frames, everywhere and at the observed
/// steps, clearly better (< 0.8×) than the action's mean motion (fitted on ids 0-31) and than
/// an untrained model of the same kind with the file's normalisation.
#[test]
fn original_data_weights_use_their_observations_on_held_out_ids() {
    let Some(data) = support::dmbn2020_dataset() else {
        return;
    };
    let (held, mean) = held_out(&data);
    for name in ["attn-2020", "dmbn-2020", "pte-2020", "pte-aug-2020"] {
        let predictor = shipped(name);
        let fresh = support::untrained(predictor.model().kind(), predictor.normalization().clone());
        support::assert_uses_its_observations(name, &predictor, &fresh, &held, &mean);
    }
}

/// The original-data issue's quality bars on the held-out ids 32-39 (5 evenly spaced
/// observations of both modalities; the first 30% for extrap), as docs/results.md reports
/// them. The paper's networks: within 0.05 rad of their observed joints, joints no worse than
/// linear interpolation, the object drawn (mask IoU at least 0.8× the nearest frame's). The
/// attentive model: within 0.02 rad at the observed steps, joints no worse than linear
/// interpolation, frames at most 0.7× the nearest frame's error with the object drawn, and
/// forecasts at most half hold-last's error in both modalities.
#[test]
fn original_data_weights_meet_the_quality_bars_on_held_out_ids() {
    let Some(data) = support::dmbn2020_dataset() else {
        return;
    };
    let (held, mean) = held_out(&data);
    let mut failures = Vec::new();
    let mut check = |name: &str, what: &str, value: f64, bar: f64| {
        println!("{name}: {what} {value:.4} (bar {bar:.4})");
        // NaN fails too.
        if value.is_nan() || value > bar {
            failures.push(format!("{name}: {what} {value:.4} above {bar:.4}"));
        }
    };
    for name in ["attn-2020", "dmbn-2020", "pte-2020", "pte-aug-2020"] {
        let predictor = shipped(name);
        let (model, baseline, _) = support::measure(&predictor, &held, Scenario::Interp, &mean);
        let attentive = name == "attn-2020";
        let observed_bar = if attentive { 0.02 } else { 0.05 };
        check(
            name,
            "joints at the observed steps",
            model.observed_joint_rmse,
            observed_bar,
        );
        check(name, "joint RMSE", model.joint_rmse, baseline.joint_rmse);
        let (iou, nearest) = (model.object_iou.unwrap(), baseline.object_iou.unwrap());
        check(name, "object IoU shortfall", 0.8 * nearest - iou, 0.0);
        if attentive {
            check(name, "image MSE", model.image_mse, 0.7 * baseline.image_mse);
            let (model, hold, _) = support::measure(&predictor, &held, Scenario::Extrap, &mean);
            check(
                name,
                "extrap joint RMSE",
                model.joint_rmse,
                0.5 * hold.joint_rmse,
            );
            check(
                name,
                "extrap image MSE",
                model.image_mse,
                0.5 * hold.image_mse,
            );
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The held-out ids 32-39 of the original data with their actions, and the actions' mean
/// motion over the training ids 0-31.
fn held_out(data: &Dataset) -> (Vec<(&str, Sequence)>, MeanMotion) {
    let read = |keep: &dyn Fn(u32) -> bool| -> Vec<(&str, Sequence)> {
        data.sequences()
            .iter()
            .filter(|s| keep(s.id))
            .map(|s| (s.action.as_str(), data.read(s, Some(64)).unwrap()))
            .collect()
    };
    let (train, held) = (read(&|id| id < 32), read(&|id| id >= 32));
    let mean = MeanMotion::fit(train.iter().map(|(a, s)| (*a, s))).unwrap();
    (held, mean)
}

/// The original-data issue's calibration bar on the held-out ids 32-39: each quality `-2020`
/// file's ±2σ joint band holds 90-98% of the truth at the unobserved steps of both scenarios.
/// (Their σ scales were fitted on these same ids, the runs' validation ids; docs/results.md
/// gives the two-fold cross-fitted coverage, which this cannot check.)
#[test]
fn original_data_weights_two_sigma_bands_hold_90_to_98_percent() {
    let Some(data) = support::dmbn2020_dataset() else {
        return;
    };
    let (held, mean) = held_out(&data);
    let failures: Vec<String> = ["attn-2020", "dmbn-2020", "pte-2020", "pte-aug-2020"]
        .iter()
        .flat_map(|name| support::two_sigma_misses(name, &shipped(name), &held, &mean))
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Without the original data, on simulated episodes (another arm, camera and object): the
/// `-2020` files still draw the observed scene clearly better (< 0.5× the image MSE) than an
/// untrained model of their kind. Their joints are not checked: the other arm's joints lie
/// radians from the simulator's (at the observed steps 1.7-2.7 rad RMSE, against 1.6-5.2 for
/// untrained models and 0.18 for the mean motion), so the joints say nothing there. The
/// attentive model returns its observed frames by construction, so it is judged on every step.
#[test]
fn original_data_weights_draw_simulated_scenes_better_than_untrained_models() {
    let seqs: Vec<(&str, Sequence)> = Action::ALL
        .map(|a| (a.name(), episode(a, 200_000, 64).unwrap()))
        .into();
    let mean = MeanMotion::fit(seqs.iter().map(|(a, s)| (*a, s))).unwrap();
    for name in ["attn-2020", "dmbn-2020", "pte-2020", "pte-aug-2020"] {
        let predictor = shipped(name);
        let kind = predictor.model().kind();
        let fresh = support::untrained(kind, predictor.normalization().clone());
        let (model, _, _) = support::measure(&predictor, &seqs, Scenario::Interp, &mean);
        let (untrained, _, _) = support::measure(&fresh, &seqs, Scenario::Interp, &mean);
        let (what, got, fresh) = if kind == ModelKind::Attn {
            ("image MSE", model.image_mse, untrained.image_mse)
        } else {
            let observed = "image MSE at the observed steps";
            (
                observed,
                model.observed_image_mse,
                untrained.observed_image_mse,
            )
        };
        println!("{name}: {what} {got:.5}, untrained {fresh:.5}");
        assert!(
            got < 0.5 * fresh,
            "{name}: {what} {got:.5}, an untrained model's {fresh:.5}"
        );
    }
}
