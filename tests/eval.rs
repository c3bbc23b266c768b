//! The paper's evaluation: the probe's head and confidence intervals on known inputs, and
//! `dmbn eval` / `dmbn probe` end to end on generated data with small models.
#![cfg(not(target_arch = "wasm32"))]

use std::process::Command;

use burn::tensor::Device;
use dmbn::data::{DatasetWriter, Normalization};
use dmbn::eval::{evenly_spaced, fit_head, mean_ci95, Encodings, HeadConfig};
use dmbn::model::{self, ModelConfig, ModelKind};
use dmbn::sim::{episode, Action};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// `k` encodings of width 8 at uniform random times; `with_time` puts t (and t²) in them.
fn synthetic(k: usize, with_time: bool, seed: u64) -> Encodings {
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
    Encodings {
        hidden: 8,
        joint: image.clone(),
        image,
        times,
    }
}

#[test]
fn the_probe_head_reads_time_when_it_is_there_and_not_otherwise() {
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
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let mut writer = DatasetWriter::create(&data).unwrap();
    for id in 0..3u32 {
        writer
            .write(
                id,
                "grasp",
                &episode(Action::Grasp, 20 + id as u64, 64).unwrap(),
            )
            .unwrap();
    }
    writer.finish().unwrap();
    let device = Device::flex();
    let mut paths = Vec::new();
    for kind in ModelKind::ALL {
        let path = tmp.path().join(format!("{kind}.dmbn"));
        let m = ModelConfig::new(kind).init(&device).unwrap();
        model::save(&path, &m, &Normalization::identity(), true).unwrap();
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
    for row in ["| Null |", "| Random |", "| DMBN |", "| DMBN-PTE |"] {
        assert!(table.contains(row), "{table}");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(probe_out.join("probe.json")).unwrap()).unwrap();
    assert_eq!(json["rows"][3]["image_mse"].as_array().unwrap().len(), 2);
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
