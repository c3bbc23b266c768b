//! The paper's evaluation: the probe's head and confidence intervals on known inputs, and
//! `dmbn eval` / `dmbn probe` end to end on generated data with small models.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::process::Command;
use std::sync::{Mutex, MutexGuard};

use burn::tensor::Device;
use dmbn::data::{Normalization, JOINTS};
use dmbn::eval::{
    diverged, evenly_spaced, fit_head, mean_ci95, split_warnings, time_variance, Divergence,
    HeadConfig, ProbeReport, ProbeResult, ProbeRow, StepEncodings, DIVERGENCE_FACTOR,
};
use dmbn::model::{ModelConfig, ModelKind};
use dmbn::sim::Action;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// burn draws weights from one generator shared by every thread, so a head fitted (or a
/// model drawn) while another test draws is not the seed's alone: the tests that draw
/// in-process take turns (the probe itself fits its heads one after another).
fn burn_generator() -> MutexGuard<'static, ()> {
    static GENERATOR: Mutex<()> = Mutex::new(());
    GENERATOR
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// `k` encodings of width 8 at uniform random times; `with_time` puts t (and t²) in them.
fn synthetic(k: usize, with_time: bool, seed: u64) -> StepEncodings {
    let mut rng = Pcg64::seed_from_u64(seed);
    let times: Vec<f32> = (0..k).map(|_| rng.random_range(0.0..1.0)).collect();
    let mut image = Vec::new();
    for &t in &times {
        let noise: Vec<f32> = (0..8).map(|_| rng.random_range(-1.0..1.0)).collect();
        if with_time {
            image.extend([3.0 * t - 1.0, t * t]);
            image.extend(&noise[2..]);
        } else {
            image.extend(noise);
        }
    }
    StepEncodings {
        hidden: 8,
        joint: image.clone(),
        image,
        times,
    }
}

#[test]
fn the_probe_head_reads_time_when_it_is_there_and_not_otherwise() {
    let _generator = burn_generator();
    let head = HeadConfig::new().with_steps(600);
    let with = fit_head(
        &synthetic(2000, true, 1),
        &synthetic(500, true, 2),
        true,
        &head,
        0,
    );
    assert!(with < 2e-3, "time in the encoding: MSE {with}");
    let without = fit_head(
        &synthetic(2000, false, 1),
        &synthetic(500, false, 2),
        false,
        &head,
        0,
    );
    // Var(t) of U(0, 1) is 1/12 ≈ 0.083: a head that learns nothing predicts the mean.
    assert!(
        (0.07..0.11).contains(&without),
        "no time in the encoding: MSE {without}"
    );
}

/// `e` with feature `j` of every step (both modalities) set to `value(step)`.
fn with_feature(mut e: StepEncodings, j: usize, value: impl Fn(usize) -> f32) -> StepEncodings {
    let h = e.hidden;
    for k in 0..e.times.len() {
        e.image[k * h + j] = value(k);
        e.joint[k * h + j] = value(k);
    }
    e
}

#[test]
fn a_feature_constant_on_the_training_steps_cannot_blow_the_probe_up() {
    let _generator = burn_generator();
    let head = HeadConfig::new().with_steps(400);
    let test_var = time_variance(&synthetic(500, true, 2).times);
    // Near-constant on the training steps (a 1e-5 jitter: its std, ~1e-5, was the divisor)
    // and far off on the test steps: the test inputs were ~1e5 standard deviations out.
    for (with_time, jitter) in [(true, 1e-5f32), (false, 1e-5), (true, 0.0), (false, 0.0)] {
        let train = with_feature(synthetic(2000, with_time, 1), 5, |k| {
            0.5 + jitter * (k % 3) as f32
        });
        let test = with_feature(synthetic(500, with_time, 2), 5, |k| 1.0 + (k % 7) as f32);
        for image in [true, false] {
            let mse = fit_head(&train, &test, image, &head, 0);
            assert!(
                mse.is_finite() && mse <= 1.5 * test_var,
                "time {with_time}, jitter {jitter}: MSE {mse} against Var(t) {test_var}"
            );
            if with_time {
                assert!(mse < 5e-3, "time {with_time}, jitter {jitter}: MSE {mse}");
            }
        }
    }
    // A whole encoding on a tiny scale is standardised as usual (the floor is relative).
    let tiny = |mut e: StepEncodings| {
        e.image.iter_mut().for_each(|v| *v *= 1e-5);
        e
    };
    let mse = fit_head(
        &tiny(synthetic(2000, true, 1)),
        &tiny(synthetic(500, true, 2)),
        true,
        &head,
        0,
    );
    assert!(mse < 5e-3, "encoding ×1e-5: MSE {mse}");
    // Non-finite values and empty sets give numbers or NaN, never a panic.
    let train = with_feature(synthetic(300, true, 1), 2, |k| {
        if k % 10 == 0 {
            f32::NAN
        } else {
            0.1
        }
    });
    assert!(fit_head(&train, &synthetic(50, true, 2), true, &head, 0).is_finite());
    let empty = StepEncodings {
        hidden: 8,
        image: Vec::new(),
        joint: Vec::new(),
        times: Vec::new(),
    };
    assert!(fit_head(&empty, &synthetic(50, true, 2), true, &head, 0).is_nan());
    assert!(fit_head(&synthetic(50, true, 2), &empty, false, &head, 0).is_nan());
}

#[test]
fn diverged_heads_and_small_splits_are_flagged() {
    let uniform: Vec<f32> = (0..=100).map(|k| k as f32 / 100.0).collect();
    let var = time_variance(&uniform);
    assert!((var - 0.0850).abs() < 1e-3, "{var}");
    assert!(time_variance(&[]).is_nan());
    assert!(!diverged(0.05, var) && !diverged(0.16, var));
    assert!(diverged(0.2, var) && diverged(19.99, var));
    assert!(diverged(f64::NAN, var) && diverged(f64::INFINITY, var));

    let row = |row, image: &[f64], joint: &[f64], bad: Vec<Divergence>| ProbeResult {
        row,
        image: mean_ci95(image),
        joint: mean_ci95(joint),
        image_mse: image.to_vec(),
        joint_mse: joint.to_vec(),
        diverged: bad,
    };
    let report = ProbeReport {
        rows: vec![
            row(
                ProbeRow::Null,
                &[0.02, 0.03],
                &[19.99, 0.05],
                vec![Divergence {
                    modality: "joint",
                    seed: 0,
                    mse: 19.99,
                }],
            ),
            row(ProbeRow::Pte, &[1e-4, 2e-4], &[1e-4, 1e-4], Vec::new()),
        ],
        train_sequences: 16,
        test_sequences: 4,
        train_steps: 930,
        test_steps: 230,
        test_time_variance: var,
        divergence_limit: 2.0 * var,
        seeds: 2,
        seconds: 1.0,
        warnings: vec!["Null joint: 1 of 2 heads diverged".into()],
    };
    assert_eq!(report.rows[0].diverged_seeds("joint"), vec![0]);
    assert!(report.rows[0].diverged_seeds("image").is_empty());
    let md = report.markdown();
    assert!(
        md.contains("| Null | 25.00 (") && md.contains(") ⚠ |"),
        "{md}"
    );
    assert!(
        md.contains("| DMBN-PTE | 0.15 (") && !md.contains("0.10) ⚠"),
        "{md}"
    );
    assert!(
        md.contains("Var(t) of the 230 test steps: 85.00 ×1e-3"),
        "{md}"
    );
    assert!(md.contains("- Null joint: 1 of 2 heads diverged"), "{md}");
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["rows"][0]["diverged"][0]["modality"], "joint");
    assert!((json["test_time_variance"].as_f64().unwrap() - var).abs() < 1e-12);

    // The split: 8 training ids, 2 test ids of ~290 steps.
    let w = split_warnings(8, 1150, 2, 291);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("only 2 test id(s)"), "{w:?}");
    let w = split_warnings(2, 200, 1, 60);
    assert_eq!(w.len(), 3, "{w:?}");
    assert!(w[1].contains("60 test steps") && w[2].contains("only 2 training id(s)"));
    assert!(split_warnings(32, 4000, 8, 900).is_empty());
}

#[test]
fn confidence_intervals_of_known_samples() {
    let m = mean_ci95(&[1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(m.mean, 3.0);
    // s = sqrt(2.5), t(0.975, 4) = 2.776: 2.776 · sqrt(2.5 / 5) = 1.9629.
    assert!((m.ci95 - 1.9629).abs() < 1e-3, "{m:?}");
    let m = mean_ci95(&[0.5, 0.5]);
    assert_eq!((m.mean, m.ci95), (0.5, 0.0));
    assert_eq!(mean_ci95(&[2.0]).ci95, 0.0);
    assert!(mean_ci95(&[]).mean.is_nan());
    assert_eq!(evenly_spaced(11, 3), vec![0, 5, 10]);
    assert_eq!(evenly_spaced(5, 9), vec![0, 1, 2, 3, 4]);
    assert_eq!(evenly_spaced(7, 1), vec![0]);
}

fn dmbn(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(args)
        .output()
        .expect("run dmbn")
}

#[test]
fn dmbn_eval_and_probe_run_end_to_end() {
    let _generator = burn_generator();
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..3, &[Action::Grasp], 20);
    let device = Device::flex();
    let mut paths = Vec::new();
    for kind in ModelKind::ALL {
        let path = tmp.path().join(format!("{kind}.dmbn"));
        let m = ModelConfig::new(kind).init(&device).unwrap();
        support::save_model(&path, &m, &Normalization::identity(JOINTS), true);
        paths.push(path.to_str().unwrap().to_string());
    }
    let d = data.to_str().unwrap();
    let out = tmp.path().join("eval");
    let o = out.to_str().unwrap();
    for mode in ["t", "p", "f"] {
        let run = dmbn(&[
            "eval",
            "--model",
            &paths[1],
            "--data",
            d,
            "--sequence",
            "1/grasp",
            "--mode",
            mode,
            "--observations",
            "5",
            "--out",
            o,
        ]);
        assert!(
            run.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert!(
            stdout.contains(&format!("{mode}-sequence")) && stdout.contains("NLL"),
            "{stdout}"
        );
        assert!(image::open(out.join("figure.png")).unwrap().height() > 500);
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("eval.json")).unwrap()).unwrap();
        assert_eq!(json["mode"], mode);
        assert_eq!(json["observed"].as_array().unwrap().len(), 5);
    }
    let run = dmbn(&[
        "eval",
        "--model",
        &paths[0],
        "--data",
        d,
        "--sequence",
        "1/grasp",
        "--mode",
        "x",
        "--observations",
        "5",
        "--out",
        o,
    ]);
    assert!(String::from_utf8_lossy(&run.stderr).contains("t, p or f"));

    let probe_out = tmp.path().join("probe");
    let run = dmbn(&[
        "probe",
        "--data",
        d,
        "--dmbn",
        &paths[0],
        "--pte",
        &paths[1],
        "--seeds",
        "2",
        "--head-steps",
        "30",
        "--test-fraction",
        "0.34",
        "--out",
        probe_out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let table = std::fs::read_to_string(probe_out.join("probe.md")).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(probe_out.join("probe.json")).unwrap()).unwrap();
    check_probe_numbers(&json, &table, 2);
    // Swapped models are refused with the file named.
    let run = dmbn(&[
        "probe",
        "--data",
        d,
        "--dmbn",
        &paths[1],
        "--pte",
        &paths[0],
        "--out",
        probe_out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("expected dmbn"),
        "{stderr}"
    );
}

/// `dmbn probe`'s numbers agree between its files: in probe.json every row (Null, Random,
/// DMBN, DMBN-PTE, in that order) holds `seeds` finite per-seed MSEs for each modality, its
/// means and 95% CIs are those of the per-seed values, its diverged heads are the ones above
/// the divergence limit; probe.md prints exactly those cells ×1e3 to two decimals (⚠ where a
/// head diverged). The image and joint heads are fitted on different encodings: their MSEs
/// differ in every row.
fn check_probe_numbers(json: &serde_json::Value, table: &str, seeds: usize) {
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"));
    let milli = |v: f64| format!("{:.2}", v * 1e3);
    let limit = f(&json["divergence_limit"]);
    assert!(limit > 0.0, "{json}");
    assert_eq!(json["seeds"].as_u64(), Some(seeds as u64));
    let lines: Vec<&str> = table.lines().filter(|l| l.starts_with("| ")).collect();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4, "{json}");
    assert_eq!(
        lines.len(),
        1 + rows.len(),
        "a header and a line per row: {table}"
    );
    for (r, (row, kind)) in rows.iter().zip(ProbeRow::ALL).enumerate() {
        assert_eq!(row["row"], serde_json::to_value(kind).unwrap());
        let name = kind.name();
        let mut cells = Vec::new();
        let mut per_modality = Vec::new();
        for modality in ["image", "joint"] {
            let mses: Vec<f64> = row[format!("{modality}_mse")]
                .as_array()
                .unwrap()
                .iter()
                .map(f)
                .collect();
            assert_eq!(mses.len(), seeds, "{name} {modality}: one MSE per seed");
            assert!(
                mses.windows(2).all(|w| w[0] != w[1]),
                "{name} {modality}: every seed fits its own head, yet {mses:?}"
            );
            assert!(
                mses.iter().all(|v| v.is_finite() && *v > 0.0),
                "{name}: {mses:?}"
            );
            let cell = &row[modality];
            let (mean, ci95) = (f(&cell["mean"]), f(&cell["ci95"]));
            let expected = mean_ci95(&mses);
            assert_eq!(cell["n"].as_u64(), Some(seeds as u64));
            assert!(
                (mean - expected.mean).abs() <= 1e-12 * expected.mean.abs(),
                "{name} {modality}: mean {mean} of {mses:?}"
            );
            assert!(
                (ci95 - expected.ci95).abs() <= 1e-9 * expected.ci95.abs().max(1e-12),
                "{name} {modality}: ci95 {ci95} of {mses:?}"
            );
            let diverged: Vec<u64> = row["diverged"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["modality"] == modality)
                .map(|d| d["seed"].as_u64().unwrap())
                .collect();
            let above: Vec<u64> = (0..seeds as u64)
                .filter(|&s| mses[s as usize] > limit)
                .collect();
            assert_eq!(diverged, above, "{name} {modality}: diverged heads");
            cells.push(format!(
                "{} ({}, {}){}",
                milli(mean),
                milli(mean - ci95),
                milli(mean + ci95),
                if diverged.is_empty() { "" } else { " ⚠" }
            ));
            per_modality.push(mses);
        }
        assert_eq!(
            lines[1 + r],
            format!("| {name} | {} | {} |", cells[0], cells[1]),
            "{table}"
        );
        assert!(
            per_modality[0]
                .iter()
                .zip(&per_modality[1])
                .all(|(a, b)| a != b),
            "{name}: image and joint heads score alike {per_modality:?}: the modality switch \
             picks the same encodings"
        );
    }
    let var_t = f(&json["test_time_variance"]);
    assert!(
        table.contains(&format!(
            "Var(t) of the {} test steps: {} ×1e-3",
            json["test_steps"],
            milli(var_t)
        )),
        "{table}"
    );
    assert!((limit - DIVERGENCE_FACTOR * var_t).abs() <= 1e-12 * limit);
}

/// A dataset of grasp episodes with the given ids (simulator seed 40 + id).
fn write_dataset(root: &std::path::Path, ids: &[u32]) {
    support::simulated_dataset(root, ids.iter().copied(), &[Action::Grasp], 40);
}

#[test]
fn dmbn_probe_tests_on_an_id_range_or_a_second_dataset() {
    let _generator = burn_generator();
    let tmp = tempfile::tempdir().unwrap();
    let (data, other) = (tmp.path().join("data"), tmp.path().join("other"));
    write_dataset(&data, &[0, 1, 2, 3]);
    write_dataset(&other, &[7]);
    let device = Device::flex();
    let mut paths = Vec::new();
    for kind in [ModelKind::Dmbn, ModelKind::Pte] {
        let path = tmp.path().join(format!("{kind}.dmbn"));
        let m = ModelConfig::new(kind).init(&device).unwrap();
        support::save_model(&path, &m, &Normalization::identity(JOINTS), true);
        paths.push(path.to_str().unwrap().to_string());
    }
    let (d, o) = (data.to_str().unwrap(), other.to_str().unwrap());
    let out = tmp.path().join("probe");
    let probe = |extra: &[&str]| {
        let mut args = vec![
            "probe",
            "--data",
            d,
            "--dmbn",
            &paths[0],
            "--pte",
            &paths[1],
            "--seeds",
            "1",
            "--head-steps",
            "20",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        dmbn(&args)
    };
    let json = || -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(out.join("probe.json")).unwrap()).unwrap()
    };

    // Fit on ids 0-1 and 3, test on id 2.
    let run = probe(&["--test-ids", "2-2"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("(ids 0-1, 3), testing on 1 sequences"),
        "{stderr}"
    );
    assert!(
        stderr.contains("warning: only 1 test id(s)")
            && stderr.contains("warning: only 3 training id(s)"),
        "{stderr}"
    );
    let j = json();
    assert_eq!(j["split"]["by"], "test-ids");
    assert_eq!(j["split"]["train_ids"], serde_json::json!([0, 1, 3]));
    assert_eq!(j["split"]["test_ids"], serde_json::json!([2]));
    assert_eq!(
        (j["train_sequences"].as_u64(), j["test_sequences"].as_u64()),
        (Some(3), Some(1))
    );
    assert!(j["test_time_variance"].as_f64().unwrap() > 0.05);
    assert!(j["warnings"].as_array().unwrap().len() >= 2, "{j}");
    let md = std::fs::read_to_string(out.join("probe.md")).unwrap();
    check_probe_numbers(&j, &md, 1);
    assert!(
        md.contains("Warnings:") && md.contains("only 1 test id(s)"),
        "{md}"
    );

    // Fit on all of --data, test on the other dataset.
    let run = probe(&["--test-data", o]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let j = json();
    assert_eq!(j["split"]["by"], "test-data");
    assert_eq!(j["split"]["train_ids"], serde_json::json!([0, 1, 2, 3]));
    assert_eq!(j["split"]["test_ids"], serde_json::json!([7]));
    assert_eq!(j["split"]["test_data"], o);

    // Bad values: clear errors naming the flag, no panic.
    for (extra, expected) in [
        (vec!["--test-ids", "3-1"], "A (3) must not exceed B (1)"),
        (vec!["--test-ids", "x"], "is not an id range A-B"),
        (vec!["--test-ids", "10-20"], "--test-ids 10-20: "),
        (
            vec!["--test-ids", "0-3"],
            "none is left to fit the heads on",
        ),
        (
            vec!["--test-ids", "1-2", "--test-data", o],
            "cannot be used with",
        ),
        (
            vec!["--test-ids", "1-2", "--test-fraction", "0.5"],
            "cannot be used with",
        ),
        (
            vec!["--test-data", "/nonexistent/dmbn"],
            "--test-data: /nonexistent/dmbn",
        ),
        (vec!["--test-fraction", "1.5"], "strictly between 0 and 1"),
    ] {
        let run = probe(&extra);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success() && stderr.contains(expected) && !stderr.contains("panicked"),
            "{extra:?}: {stderr}"
        );
    }
    let run = probe(&["--test-ids", "10-20"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("no sequence with an id in 10..=20 (its ids: 0-3)"),
        "{stderr}"
    );
}
