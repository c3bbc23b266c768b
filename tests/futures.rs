//! Many futures (crate::futures): autoregressive samples of the page's default model are
//! coherent trajectories (smooth, unlike independent draws from the per-step Gaussians), spread
//! where the future is ambiguous, seeded and deterministic; `dmbn sample` writes them and
//! refuses bad settings; `dmbn imitate --samples` performs them.
#![cfg(not(target_arch = "wasm32"))]

#[path = "golden/futures.rs"]
mod golden_futures;
mod support;

use std::process::{Command, Output};

use dmbn::data::Joints;
use dmbn::futures::{
    draw_futures, sample_trajectories, sample_unobserved, FutureScores, Order, Sampling,
};
use dmbn::imitate::{imitate_futures, Task};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};

fn predictor() -> Predictor {
    Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap()
}

fn dmbn(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(args)
        .output()
        .expect("run dmbn")
}

/// Mean absolute second difference of each arm joint over the steps `from..`: how jagged.
fn roughness(joints: &Joints, from: usize) -> f64 {
    let arm = joints.width() - 1;
    let mut sum = 0.0;
    let mut n = 0;
    for k in from + 1..joints.len() - 1 {
        for j in 0..arm {
            let d2 = joints[k + 1][j] - 2.0 * joints[k][j] + joints[k - 1][j];
            sum += d2.abs() as f64;
            n += 1;
        }
    }
    sum / n as f64
}

/// A push of `seed` to finish from its first 30%: the demonstration, its observed steps, their
/// observations and the times of the steps to imagine.
fn push_to_finish(seed: u64) -> (dmbn::data::Sequence, Vec<usize>, Observations, Vec<f32>) {
    let demo = episode(Action::Move, seed, 64).unwrap();
    let steps = Task::Finish.steps(demo.len(), 5).unwrap();
    let observations = Observations::from_sequence(&demo, &steps.observed).unwrap();
    let future = demo.times()[steps.predicted_from..].to_vec();
    (demo, steps.observed, observations, future)
}

/// Each future's drawn steps' joints, in the order drawn, one row per future.
fn drawn(p: &Predictor, o: &Observations, future: &[f32], s: &Sampling) -> Vec<Vec<f32>> {
    let futures = draw_futures(p, o, future, 0.5, s).unwrap();
    (futures.iter())
        .map(|f| f.drawn.iter().flat_map(|(_, j)| j.clone()).collect())
        .collect()
}

#[test]
fn sampled_futures_are_smooth_spread_and_deterministic() {
    let p = predictor();
    let demo = episode(Action::Move, 424_242, 64).unwrap();
    let steps = Task::Finish.steps(demo.len(), 5).unwrap();
    let observations = Observations::from_sequence(&demo, &steps.observed).unwrap();
    let times = demo.times();
    let future = &times[steps.predicted_from..];
    // Drawn as such (no representatives), so that future s is the same whatever S.
    let sampling = Sampling {
        samples: 6,
        oversample: 1,
        ..Sampling::default()
    };
    let futures = sample_trajectories(&p, &observations, future, &times, 0.5, &sampling).unwrap();
    assert_eq!(futures.len(), 6);
    let from = steps.predicted_from;
    // Coherent: each future is as smooth as a trajectory, unlike the per-step marginals drawn
    // independently (the same Gaussians, no conditioning between steps).
    let marginal = p.predict(&observations, &times, 0.5).unwrap();
    let mut rng = 12345u64;
    let mut uniform = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 11) as f64 / (1u64 << 53) as f64).max(1e-12)
    };
    let draws: Vec<f32> = (0..demo.len())
        .flat_map(|k| {
            let (m, s) = (marginal.joint_mean_at(k), marginal.joint_sigma_at(k));
            m.iter().zip(s).map(|(m, s)| (*m, *s)).collect::<Vec<_>>()
        })
        .map(|(m, s)| {
            let z = (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
            m + s * z as f32
        })
        .collect();
    let independent = Joints::new(demo.joints.width(), draws).unwrap();
    let jagged = roughness(&independent, from);
    for (s, f) in futures.iter().enumerate() {
        let r = roughness(f, from);
        assert!(
            r < jagged / 5.0,
            "future {s}: roughness {r} vs independent draws' {jagged}"
        );
    }
    // Spread: where the push ends is not in its first 30%, so the futures' last rows differ.
    let last = demo.len() - 1;
    let spread = futures
        .iter()
        .map(|f| (f[last][0] - futures[0][last][0]).abs())
        .fold(0.0f32, f32::max);
    assert!(spread > 1e-3, "the futures end alike: {spread}");
    // Seeded: the same futures again, future s the same whatever S; another seed, others.
    let again = sample_trajectories(&p, &observations, future, &times, 0.5, &sampling).unwrap();
    assert_eq!(futures, again);
    let two = Sampling {
        samples: 2,
        ..sampling
    };
    let first_two = sample_trajectories(&p, &observations, future, &times, 0.5, &two).unwrap();
    assert_eq!(first_two[..], futures[..2]);
    let reseeded = Sampling {
        seed: 1,
        ..sampling
    };
    let other = sample_trajectories(&p, &observations, future, &times, 0.5, &reseeded).unwrap();
    assert_ne!(other, futures);
    // Random order draws the same grid in another order.
    let random = Sampling {
        order: Order::Random,
        grid: 3,
        ..sampling
    };
    let drawn = draw_futures(&p, &observations, future, 0.5, &random).unwrap();
    let mut grid: Vec<f32> = drawn[0].drawn.iter().map(|(t, _)| *t).collect();
    assert_eq!(grid.len(), 3);
    grid.sort_by(f32::total_cmp);
    assert_eq!(*grid.last().unwrap(), *future.last().unwrap());
    // Scores: the mean's energy score is its RMSE; the samples' are finite.
    let mean = Joints::new(demo.joints.width(), marginal.joint_mean.clone()).unwrap();
    let imagined: Vec<usize> = (from..demo.len()).collect();
    let scores = FutureScores::of(&futures, &mean, &demo.joints, &imagined);
    assert!(
        scores.energy.is_finite() && scores.energy > 0.0,
        "{scores:?}"
    );
    assert!(scores.best_rmse <= scores.sample_rmse, "{scores:?}");
    // Bad settings are named.
    let none = Sampling {
        samples: 0,
        ..sampling
    };
    let err = draw_futures(&p, &observations, future, 0.5, &none).unwrap_err();
    assert!(err.to_string().contains("samples"), "{err}");
    let err = draw_futures(&p, &observations, &[], 0.5, &sampling).unwrap_err();
    assert!(err.to_string().contains("target_times"), "{err}");
}

/// Oversampled: S representatives of K × S futures, each one of those drawn (the K × S of
/// plain sampling with the same seed), spread over them better than the first S drawn.
#[test]
fn oversampled_futures_are_representatives_of_more_draws() {
    let p = predictor();
    let (_, _, observations, future) = push_to_finish(434_343);
    let future = &future[..];
    let sampling = Sampling {
        samples: 6,
        oversample: 1,
        ..Sampling::default()
    };
    let kept = Sampling {
        oversample: 4,
        ..sampling
    };
    let all = Sampling {
        samples: 24,
        ..sampling
    };
    let (kept, all) = (
        drawn(&p, &observations, future, &kept),
        drawn(&p, &observations, future, &all),
    );
    assert_eq!(kept.len(), 6);
    for (i, k) in kept.iter().enumerate() {
        assert!(all.contains(k), "kept future {i} was not drawn");
        assert!(!kept[..i].contains(k), "future {i} kept twice");
    }
    // Covering radius: how far the draws are from the nearest of the six.
    let radius = |six: &[Vec<f32>]| {
        (all.iter())
            .map(|x| {
                (six.iter())
                    .map(|y| x.iter().zip(y).map(|(a, b)| (a - b).powi(2)).sum::<f32>())
                    .fold(f32::INFINITY, f32::min)
            })
            .sum::<f32>()
    };
    assert!(
        radius(&kept) < radius(&all[..6]),
        "representatives {} vs the first six {}",
        radius(&kept),
        radius(&all[..6])
    );
    let bad = Sampling {
        oversample: 0,
        ..sampling
    };
    let err = draw_futures(&p, &observations, future, 0.5, &bad).unwrap_err();
    assert!(err.to_string().contains("oversample"), "{err}");
}

#[test]
fn bootstrapped_futures_see_resampled_observations_and_keep_the_latest() {
    let p = predictor();
    let (demo, observed, observations, future) = push_to_finish(454_545);
    let sampling = Sampling {
        samples: 6,
        oversample: 1,
        ..Sampling::default()
    };
    let draw = |s: &Sampling, o: &Observations| drawn(&p, o, &future, s);
    let fixed = Sampling {
        bootstrap: false,
        ..sampling
    };
    let (booted, all) = (draw(&sampling, &observations), draw(&fixed, &observations));
    assert_ne!(booted, all, "bootstrap resamples changed no future");
    assert_eq!(booted, draw(&sampling, &observations), "not deterministic");
    // A future's first drawn step, given a resample, differs from the one given all the
    // observations only by what the resample left out: with one observation there is nothing
    // to resample, and the futures are those drawn from all of it.
    let latest = Observations::from_sequence(&demo, &observed[observed.len() - 1..]).unwrap();
    assert_eq!(draw(&sampling, &latest), draw(&fixed, &latest));
    // Resamples that kept an older observation in the latest's place would restart the arm
    // from an older pose: every future's first drawn step stays near the one drawn from all.
    let first = |x: &[Vec<f32>]| x.iter().map(|f| f[0]).collect::<Vec<f32>>();
    let (b, a) = (first(&booted), first(&all));
    let spread = |v: &[f32]| {
        v.iter().cloned().fold(f32::MIN, f32::max) - v.iter().cloned().fold(f32::MAX, f32::min)
    };
    assert!(
        spread(&b) < 4.0 * spread(&a) + 0.05,
        "booted {b:?} all {a:?}"
    );
}

#[test]
fn every_sampled_future_is_performed() {
    let p = predictor();
    let demo = episode(Action::Grasp, 515_151, 64).unwrap();
    let sampling = Sampling {
        samples: 3,
        ..Sampling::default()
    };
    let performed = imitate_futures(&p, &demo, Action::Grasp, Task::Finish, 5, 0.5, &sampling)
        .unwrap()
        .unwrap();
    assert_eq!(performed.len(), 3);
    let from = performed[0].predicted_from;
    for imitation in &performed {
        assert_eq!(imitation.trajectory.len(), demo.len());
        // The observed 30% is performed as recorded, the rest as the future imagined.
        assert_eq!(
            imitation.trajectory[from - 1],
            demo.joints[from - 1].to_vec()
        );
    }
    assert_ne!(performed[0].trajectory, performed[1].trajectory);
}

#[test]
fn dmbn_sample_writes_the_futures_and_refuses_bad_settings() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, [0], &[Action::Move], 600_000);
    let model = support::asset("models/attn-sim.dmbn");
    let out = tmp.path().join("out");
    let run = |extra: &[&str], out: &std::path::Path| {
        let mut args = vec!["sample", "--model", model.to_str().unwrap()];
        args.extend(["--data", data.to_str().unwrap(), "--sequence", "0/move"]);
        args.extend([
            "--observe",
            "0,5,10",
            "--samples",
            "3",
            "--out",
            out.to_str().unwrap(),
        ]);
        args.extend(extra);
        dmbn(&args)
    };
    let ok = run(&[], &out);
    let said =
        String::from_utf8_lossy(&ok.stdout).to_string() + &String::from_utf8_lossy(&ok.stderr);
    assert!(ok.status.success(), "{said}");
    assert!(said.contains("energy score"), "{said}");
    for file in ["fan.png", "strips.png", "samples.csv", "samples.json"] {
        assert!(out.join(file).is_file(), "{file}");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("samples.json")).unwrap()).unwrap();
    let futures = json["futures"].as_array().unwrap();
    assert_eq!(futures.len(), 3);
    let steps = json["times"].as_array().unwrap().len();
    assert_eq!(futures[0]["joints"].as_array().unwrap().len(), steps);
    assert_eq!(
        futures[0]["drawn"].as_array().unwrap().len(),
        Sampling::default().grid,
        "the default grid"
    );
    assert!(json["scores"]["energy"].as_f64().unwrap() > 0.0);
    // The strip: the truth, the mean and 3 futures, 8 frames each.
    let strips = image::open(out.join("strips.png")).unwrap();
    assert_eq!((strips.width(), strips.height()), (8 * 64, 5 * 64));
    let csv = std::fs::read_to_string(out.join("samples.csv")).unwrap();
    assert!(
        csv.starts_with("sample,step,time,\"joint 0\""),
        "{}",
        &csv[..80]
    );
    assert_eq!(csv.lines().count(), 1 + 4 * steps);
    // The same seed, the same file.
    let again = tmp.path().join("again");
    assert!(run(&[], &again).status.success());
    assert_eq!(
        std::fs::read(out.join("samples.json")).unwrap(),
        std::fs::read(again.join("samples.json")).unwrap()
    );
    // Bad settings: an error that names them, nothing written.
    let bad = tmp.path().join("bad");
    for (extra, needle) in [
        (&["--samples", "0"][..], "samples"),
        (&["--grid", "0"][..], "grid"),
        (&["--order", "backwards"][..], "left-to-right or random"),
        (&["--components", "0"][..], "1 or more, or all"),
        (&["--bootstrap", "maybe"][..], "--bootstrap"),
        (&["--stage", "maybe"][..], "--stage"),
        (&["--end-temperature", "9"][..], "`end_temperature` is 9"),
    ] {
        let o = run(extra, &bad);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(needle),
            "{extra:?}: {err}"
        );
        assert!(!bad.exists(), "{extra:?} wrote {}", bad.display());
    }
    let all: Vec<String> = (0..steps).map(|k| k.to_string()).collect();
    let o = dmbn(&[
        "sample",
        "--model",
        model.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--sequence",
        "0/move",
        "--observe",
        &all.join(","),
        "--out",
        bad.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("nothing is left to imagine"));
}

#[test]
fn dmbn_imitate_samples_reports_validity_and_coverage() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, [0, 1], &Action::ALL, 610_000);
    let json = tmp.path().join("imitate.json");
    let o = dmbn(&[
        "imitate",
        "--model",
        support::asset("models/attn-sim.dmbn").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--task",
        "finish",
        "--samples",
        "2",
        "--json",
        json.to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(said.contains("| validity | coverage |"), "{said}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rows = report[0]["futures"]["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "a row per action");
    for row in rows {
        assert_eq!(row["demonstrations"], 2);
        assert_eq!(row["performed"], 4);
        let v = row["validity"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&v));
    }
    assert_eq!(
        report[0]["future_performances"].as_array().unwrap().len(),
        8
    );
}

/// The golden case's observations (the first 30% at 3 steps) and every step's time.
fn golden_case() -> (dmbn::data::Sequence, Observations, Vec<f32>) {
    let demo = episode(Action::Move, golden_futures::SEED, 64).unwrap();
    let steps = Task::Finish.steps(demo.len(), 5).unwrap();
    let observations = Observations::from_sequence(&demo, &steps.observed).unwrap();
    let times = demo.times();
    (demo, observations, times)
}

#[test]
fn the_page_s_default_model_samples_the_golden_futures() {
    // tests/web.rs: `Model.sample` in wasm gives the same within 1e-4.
    let p = Predictor::from_bytes(golden_futures::MODEL).unwrap();
    let (_, observations, times) = golden_case();
    let sampling = Sampling {
        samples: golden_futures::SAMPLES,
        seed: golden_futures::SAMPLE_SEED,
        ..Sampling::default()
    };
    let observed = p.encode_contexts(&observations).unwrap();
    let futures =
        sample_unobserved(&p, &observed, &times, golden_futures::BLEND, &sampling).unwrap();
    let got: Vec<f32> = futures.iter().flat_map(|f| f.values().to_vec()).collect();
    if std::env::var_os("DMBN_BLESS").is_some() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/futures.json");
        std::fs::write(path, serde_json::to_string(&got).unwrap()).unwrap();
        return;
    }
    let want = golden_futures::expected();
    assert_eq!(got.len(), want.len());
    let worst = got
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(
        worst <= 1e-6,
        "the futures moved from the golden ones by {worst}"
    );
    // Every target observed: nothing to imagine, said so.
    let err = sample_unobserved(&p, &observed, &observations.times, 0.5, &sampling).unwrap_err();
    assert!(err.to_string().contains("only observed times"), "{err}");
}
