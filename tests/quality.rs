//! The quality benchmark: the golden scores of the default model (which the wasm tests must
//! reproduce), `dmbn score` end to end, the bars every shipped model must clear on simulated
//! episodes it never saw, and the default model's figures there, which it must keep to within
//! 5%.
#![cfg(not(target_arch = "wasm32"))]

#[path = "golden/score.rs"]
mod golden_score;
mod support;

use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

use dmbn::data::{Normalization, Sequence, JOINTS};

use dmbn::predict::Predictor;
use dmbn::quality::{score_sequence, MeanMotion, Quality, Scenario};
use dmbn::sim::{episode, Action};
use golden_score as golden;

/// The shipped simulator weights besides `attn-sim` (the page's default, which has its own
/// tests below): every one must read its observations.
const SHIPPED_SIM: [&str; 3] = ["dmbn-sim", "pte-sim", "pte-aug-sim"];

#[test]
fn default_model_reproduces_the_golden_scores() {
    let predictor = Predictor::from_bytes(golden::MODEL).unwrap();
    let seq = episode(Action::Grasp, golden::SEED, 64).unwrap();
    let samples: Vec<Vec<f64>> = golden::SCENARIOS
        .iter()
        .map(|&scenario| {
            let s = score_sequence(
                &predictor,
                &seq,
                "grasp",
                scenario,
                golden::OBSERVATIONS,
                golden::BLEND,
                None,
            )
            .unwrap()
            .expect("long enough");
            golden::sample(&s.model.finish(), &s.baseline.finish())
        })
        .collect();
    if std::env::var_os("DMBN_BLESS").is_some() {
        assert!(
            std::env::var_os("CI").is_none(),
            "DMBN_BLESS is refused under CI"
        );
        let json: Vec<Vec<Option<f64>>> = samples
            .iter()
            .map(|row| row.iter().map(|v| (!v.is_nan()).then_some(*v)).collect())
            .collect();
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/score.json");
        std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
        return;
    }
    let expected = golden::expected();
    assert_eq!(
        samples.len(),
        expected.len(),
        "re-bless tests/golden/score.json with DMBN_BLESS=1"
    );
    for (got, want) in samples.iter().zip(&expected) {
        let (diff, at) = golden::max_diff(got, want);
        assert!(
            diff < 1e-6,
            "differs from tests/golden/score.json by {diff} at {at}"
        );
    }
    // The baseline reproduces its observations (up to rounding the frames to f32).
    assert_eq!(samples[0][9 + 3], 0.0);
    assert!(samples[0][9 + 4] < 1e-12);
}

/// Unseen episodes per action behind the default model's bars. Its measures vary over
/// episodes: the standard deviation of each figure over sets of 80 episodes per action is
/// 1.1-2.8% of it (bootstrapped from 100 per action, 2026-12-07: joint RMSE 1.5% between the
/// observations and 2.4% forecasting, image MSE 1.1% and 1.8%, object IoU 2.5%, the joints
/// read from frames alone 2.5-2.8%; at 3 per action, as these tests had, 6-15%; at 10,
/// 3-7%). So a model 10% worse than the shipped file overall is 10% ± 2.8% worse on these
/// episodes, and fails bars 5% above the shipped figures about 19 times in 20 even where the
/// noise is largest, while an equally good one passes them as often. About 50 s of the tests'
/// build on one core (0.11 s a sequence and measurement).
const EPISODES: usize = 80;

/// How much worse than the shipped file's figure on the unseen episodes the default model may
/// be (see [`EPISODES`]): half the 10% regression the bars must catch.
const TOLERANCE: f64 = 0.05;

/// The first `per_action` of [`EPISODES`] unseen episodes per action (seeds 200,000 on; the
/// simulator weights trained on seeds 1000-2999 and had their σ calibrated on
/// 700000-700029), both actions: made once per test binary, which every test shares.
fn unseen(per_action: usize) -> &'static [(&'static str, Sequence)] {
    static UNSEEN: OnceLock<Vec<(&'static str, Sequence)>> = OnceLock::new();
    let all = UNSEEN.get_or_init(|| {
        (0..EPISODES as u64)
            .flat_map(|i| Action::ALL.map(|a| (a.name(), episode(a, 200_000 + i, 64).unwrap())))
            .collect()
    });
    &all[..2 * per_action.min(EPISODES)]
}

/// Each action's mean motion over 10 other unseen episodes.
fn mean_motion() -> &'static MeanMotion {
    static MEAN: OnceLock<MeanMotion> = OnceLock::new();
    MEAN.get_or_init(|| {
        let reference: Vec<(&str, Sequence)> = (0..10)
            .flat_map(|i| Action::ALL.map(|a| (a.name(), episode(a, 300_000 + i, 64).unwrap())))
            .collect();
        MeanMotion::fit(reference.iter().map(|(a, s)| (*a, s))).unwrap()
    })
}

/// The default model's, the baseline's and the mean motion's measures on every unseen episode
/// in `scenario` with blend `blend` (0.5, or 1: frames alone): measured once per test binary.
fn default_model(scenario: Scenario, blend: f32) -> &'static (Quality, Quality, Quality) {
    static MEASURED: [OnceLock<(Quality, Quality, Quality)>; 3] =
        [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let slot = match (scenario, blend) {
        (Scenario::Interp, 0.5) => 0,
        (Scenario::Extrap, 0.5) => 1,
        (Scenario::Interp, 1.0) => 2,
        _ => unreachable!("not measured: {scenario} at blend {blend}"),
    };
    MEASURED[slot].get_or_init(|| {
        let predictor = Predictor::from_bytes(golden::MODEL).unwrap();
        let measured = support::measure_blended(
            &predictor,
            unseen(EPISODES),
            scenario,
            blend,
            mean_motion(),
        );
        println!(
            "{scenario}, blend {blend}, {EPISODES} episodes per action:\nmodel: {:?}\nbaseline: {:?}",
            measured.0, measured.1
        );
        measured
    })
}

/// A model that ignores its observations scores like the action's mean motion at best:
/// every shipped simulator model must do clearly better on episodes it never saw, and better
/// than an untrained model of its kind. A property, not a regression bar: each model's
/// measures are at most 0.36 of the mean motion's (pte-sim's image MSE at the observed steps),
/// the bar 0.8, and on 3 episodes per action they vary by 7-14% (measured on 30 per action,
/// 2026-12-07), so 3 suffice.
#[test]
fn shipped_simulator_models_use_their_observations() {
    uses_its_observations(&SHIPPED_SIM);
}

/// The page's default, trained: its untrained self already starts from the linear
/// interpolation of the observations, and training must improve on that too.
#[test]
fn the_default_model_improves_on_its_untrained_self() {
    uses_its_observations(&["attn-sim"]);
}

fn uses_its_observations(names: &[&str]) {
    let (seqs, mean) = (unseen(3), mean_motion());
    for &name in names {
        let predictor = Predictor::load(support::asset(&format!("models/{name}.dmbn"))).unwrap();
        let fresh = support::untrained(predictor.model().kind(), Normalization::identity(JOINTS));
        support::assert_uses_its_observations(name, &predictor, &fresh, seqs, mean);
    }
}

/// The bars for the page's default model, on the unseen episodes: with 5 evenly
/// spaced observations its joints are no worse than linear interpolation, its frames no worse
/// than the nearest observed frame and the object visible in them (mask IoU >= 0.3);
/// observing the first 30%, the rest of the joints at most half the error of holding the last
/// observation (the frames: the next test). The 0.02 rad at the observed steps is not
/// among them: at blend 0.5 the attentive model returns its observed joints by construction,
/// so it could not fail; the joints it reads at the observed steps from frames alone take its
/// place ([`from_frames_alone_the_default_model_reads_the_joints_as_well_as_it_shipped`]).
#[test]
fn the_default_model_beats_the_trivial_baselines() {
    let (model, baseline, _) = default_model(Scenario::Interp, 0.5);
    assert!(
        model.joint_rmse <= baseline.joint_rmse,
        "interp joint RMSE {} vs linear {}",
        model.joint_rmse,
        baseline.joint_rmse
    );
    assert!(
        model.image_mse <= baseline.image_mse,
        "interp image MSE {} vs nearest frame {}",
        model.image_mse,
        baseline.image_mse
    );
    let iou = model
        .object_iou
        .expect("the object is visible in the true frames");
    assert!(iou >= 0.3, "object IoU {iou}");
    let (model, baseline, _) = default_model(Scenario::Extrap, 0.5);
    assert!(
        model.joint_rmse <= 0.5 * baseline.joint_rmse,
        "extrap joint RMSE {} vs hold-last {}",
        model.joint_rmse,
        baseline.joint_rmse
    );
}

/// The last bar: observing the first 30%, the frames of the rest at most half the error of
/// holding the last observation.
#[test]
fn the_default_model_halves_hold_last_s_frame_error_when_forecasting() {
    let (model, baseline, _) = default_model(Scenario::Extrap, 0.5);
    assert!(
        model.image_mse <= 0.5 * baseline.image_mse,
        "extrap image MSE {} vs hold-last {}",
        model.image_mse,
        baseline.image_mse
    );
}

/// One of the default model's measures on the unseen episodes against the shipped file's
/// figure there: a message when it is more than [`TOLERANCE`] worse (`higher`: whether higher
/// is better).
fn regressed(what: &str, got: f64, shipped: f64, higher: bool) -> Option<String> {
    let (bar, worse) = if higher {
        let bar = shipped * (1.0 - TOLERANCE);
        (bar, got < bar)
    } else {
        let bar = shipped * (1.0 + TOLERANCE);
        (bar, got > bar)
    };
    println!("{what}: {got:.6} (shipped {shipped:.6}, bar {bar:.6})");
    worse.then(|| format!("{what} {got:.6}: the shipped file's {shipped:.6}, the bar {bar:.6}"))
}

/// The bars leave the page's default model room to get much worse (its joint error
/// between the observations is 0.6× linear interpolation's, forecasting 0.26× holding the
/// last observation): on the unseen episodes it must stay within [`TOLERANCE`] of the shipped
/// file's figures, so that a model 10% worse fails (see [`EPISODES`]). The figures are
/// `attn-sim.dmbn`'s as shipped (2026-12-07, 80 episodes per action); a better file ships
/// with its own (the test prints them).
#[test]
fn the_default_model_is_no_worse_than_it_shipped() {
    let (interp, _, _) = default_model(Scenario::Interp, 0.5);
    let (extrap, _, _) = default_model(Scenario::Extrap, 0.5);
    let iou = interp.object_iou.expect("the object is visible");
    let failures: Vec<String> = [
        regressed("interp joint RMSE", interp.joint_rmse, 0.02524, false),
        regressed("interp image MSE", interp.image_mse, 0.001632, false),
        regressed("interp object IoU", iou, 0.5576, true),
        regressed("extrap joint RMSE", extrap.joint_rmse, 0.03957, false),
        regressed("extrap image MSE", extrap.image_mse, 0.002551, false),
    ]
    .into_iter()
    .flatten()
    .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// From frames alone (blend 1; the page's Imitate mode) the default model reads the joints at
/// the 5 observed steps, and fills in the rest, within [`TOLERANCE`] of the shipped file's
/// figures on the unseen episodes: what the imitation benchmark performs from. It takes the
/// place of the 0.02 rad at the observed steps, which the attentive model meets by
/// construction at blend 0.5 (it returns its observed joints) and misses from frames alone
/// (0.0233 rad). The file without its joint stage fails both bars (measured: 0.0329 and
/// 0.0371 rad, 41% and 29% worse; at blend 0.5 it is the same model).
#[test]
fn from_frames_alone_the_default_model_reads_the_joints_as_well_as_it_shipped() {
    let (frames, _, motion) = default_model(Scenario::Interp, 1.0);
    // The frames are read, not ignored: far below the mean motion's error there.
    assert!(
        frames.observed_joint_rmse < 0.3 * motion.observed_joint_rmse,
        "{} vs the mean motion's {}",
        frames.observed_joint_rmse,
        motion.observed_joint_rmse
    );
    let failures: Vec<String> = [
        regressed(
            "joint RMSE at the observed steps",
            frames.observed_joint_rmse,
            0.02330,
            false,
        ),
        regressed("joint RMSE", frames.joint_rmse, 0.02884, false),
    ]
    .into_iter()
    .flatten()
    .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn dmbn_score_prints_tables_and_writes_json() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..2, &Action::ALL, 400_000);
    let model = support::asset("models/dmbn-sim.dmbn");
    let json = tmp.path().join("score.json");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .arg("score")
            .args(args)
            .output()
            .unwrap()
    };
    let plot = tmp.path().join("calibration.png");
    let (data_arg, model_arg, json_arg, plot_arg) = (
        data.to_str().unwrap(),
        model.to_str().unwrap(),
        json.to_str().unwrap(),
        plot.to_str().unwrap(),
    );
    let out = run(&[
        "--model",
        model_arg,
        "--data",
        data_arg,
        "--ids",
        "0-0",
        "--mean-ids",
        "1-1",
        "--json",
        json_arg,
        "--plot",
        plot_arg,
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for row in [
        "| dmbn-sim.dmbn | 2 |",
        "| linear joints + nearest frame | 2 |",
        "| hold last observation | 2 |",
        "| mean motion of the action | 2 |",
    ] {
        assert!(stdout.contains(row), "no row {row:?} in\n{stdout}");
    }
    let reports: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let reports = reports.as_array().unwrap();
    assert_eq!(reports.len(), 2, "interp and extrap");
    assert_eq!(reports[0]["scenario"], "interp");
    assert_eq!(reports[1]["observations"], 3);
    let rows = reports[0]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[0]["model"], true);
    assert_eq!(
        rows[1]["quality"]["observed_joint_rmse"], 0.0,
        "the baseline holds its observations"
    );
    assert!(rows[0]["quality"]["joint_rmse"].as_f64().unwrap() > 0.0);
    // The model's calibration (none for a baseline), in the table, the JSON and the plot.
    assert_eq!(
        stdout
            .matches("calibration at the unobserved steps")
            .count(),
        2
    );
    let calibration = &rows[0]["quality"]["calibration"];
    for what in ["joints", "pixels", "moving_pixels"] {
        let c = &calibration[what];
        let (one, two) = (
            c["one_sigma"].as_f64().unwrap(),
            c["two_sigma"].as_f64().unwrap(),
        );
        assert!(0.0 < one && one <= two && two <= 1.0, "{what}: {c}");
        assert_eq!(c["curve"].as_array().unwrap().len(), 10);
        assert!(c["sigma_to_rmse"].as_f64().unwrap() > 0.0);
    }
    assert!(
        calibration["moving_pixels"]["values"].as_u64() < calibration["pixels"]["values"].as_u64()
    );
    assert!(rows[1]["quality"]["calibration"].is_null());
    let png = image::open(&plot).unwrap();
    assert_eq!((png.width(), png.height()), (900, 760));

    for (args, expected) in [
        (
            vec!["--model", model_arg, "--data", data_arg, "--ids", "5-9"],
            "no sequence with an id",
        ),
        (
            vec!["--model", model_arg, "--data", data_arg, "--ids", "9-5"],
            "A (9) must not exceed B (5)",
        ),
        (
            vec![
                "--model",
                model_arg,
                "--data",
                data_arg,
                "--observations",
                "1",
            ],
            "observations",
        ),
        (
            vec!["--model", "/no/such.dmbn", "--data", data_arg],
            "/no/such.dmbn",
        ),
        (
            vec!["--model", model_arg, "--data", "/no/such/data"],
            "/no/such/data",
        ),
    ] {
        let out = run(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(expected),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

/// `dmbn calibrate` writes the model with joint σ scales under which ±2σ holds 95% of the
/// joints of the sequences it was fitted on, between the observations and beyond them (both
/// scenarios pooled), and names what is wrong.
#[test]
fn dmbn_calibrate_scales_the_joint_sigma_to_cover_95_percent() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..3, &Action::ALL, 410_000);
    let model = support::asset("models/attn-sim.dmbn");
    let out = tmp.path().join("calibrated.dmbn");
    let run = |args: Vec<std::ffi::OsString>| {
        Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .arg("calibrate")
            .args(args)
            .output()
            .unwrap()
    };
    let args = |ids: &str, model: &Path| -> Vec<std::ffi::OsString> {
        [
            "--model".as_ref(),
            model.as_os_str(),
            "--data".as_ref(),
            data.as_os_str(),
            "--ids".as_ref(),
            ids.as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ]
        .iter()
        .map(|a| a.to_os_string())
        .collect()
    };
    let ok = run(args("0-2", &model));
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let stdout = String::from_utf8_lossy(&ok.stdout);
    assert_eq!(stdout.matches("now 95.5%").count(), 2, "{stdout}");
    let bytes = std::fs::read(&out).unwrap();
    let header = dmbn::model::read_header(&bytes).unwrap();
    // The file's own scale (attn-sim is calibrated) times the fitted factors.
    let (before, after) = (
        dmbn::model::read_header(&std::fs::read(&model).unwrap())
            .unwrap()
            .joint_sigma_scales(),
        header.joint_sigma_scales(),
    );
    let forecast = after.forecast.expect("the extrap scenario forecasts");
    assert!(after.between != before.between, "{before:?} {after:?}");
    assert!(forecast != after.between, "{after:?}");
    let calibrated = Predictor::from_bytes(&bytes).unwrap();
    let dataset = dmbn::data::Dataset::open(&data).unwrap();
    let mut z = dmbn::quality::JointZScores::default();
    for r in dataset.sequences() {
        let seq = dataset.read(r, Some(64)).unwrap();
        for scenario in Scenario::ALL {
            z.extend(dmbn::quality::joint_z_scores(&calibrated, &seq, scenario, 5, 0.5).unwrap());
        }
    }
    // Each side of the observations' span is now covered 95.45%, up to the quantile's step.
    for (side, z) in [("between", &z.between), ("forecast", &z.forecast)] {
        let covered = z.iter().filter(|&&v| v <= 2.0).count() as f64 / z.len() as f64;
        assert!(
            (covered - 0.9545).abs() < 0.005,
            "{side}: {covered} of {} values",
            z.len()
        );
    }
    // Ids with no sequence, and a file that is not there, are named.
    let none = run(args("7-9", &model));
    assert!(String::from_utf8_lossy(&none.stderr).contains("no sequence with an id in 7-9"));
    let missing = tmp.path().join("missing.dmbn");
    let gone = run(args("0-2", &missing));
    assert!(!gone.status.success());
    assert!(String::from_utf8_lossy(&gone.stderr).contains("missing.dmbn"));
}

/// The original-data issue's calibration bar: every shipped simulator model's ±2σ joint band
/// holds 90-98% of the truth at the steps it did not observe, on episodes that neither its
/// training (seeds 1000-2999) nor its σ scale (`dmbn calibrate` on seeds 700000-700029) saw,
/// in both scenarios (a calibrated Gaussian: 95.4%).
#[test]
fn shipped_simulator_models_two_sigma_bands_hold_90_to_98_percent() {
    let seqs: Vec<(&str, Sequence)> = (0..8)
        .flat_map(|i| Action::ALL.map(|a| (a.name(), episode(a, 100_000 + i, 64).unwrap())))
        .collect();
    let mean = mean_motion();
    let failures: Vec<String> = std::iter::once("attn-sim")
        .chain(SHIPPED_SIM)
        .flat_map(|name| {
            let predictor =
                Predictor::load(support::asset(&format!("models/{name}.dmbn"))).unwrap();
            support::two_sigma_misses(name, &predictor, &seqs, mean)
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}
