//! The latent path (crate::model::LatentPath): a global z per sequence, drawn once per sampled
//! future. A fresh path adds nothing (a trained file given one predicts as before); once it
//! adds something, futures drawn through it differ, each one smooth, seeded, the same whatever
//! S; the path survives the model file; `train --latent` adds one and logs its KL, and bad
//! settings are refused.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::process::Command;

use burn::module::Param;
use burn::tensor::{Device, Distribution, Tensor};
use dmbn::futures::{draw_futures, trajectories, Method, Sampling};
use dmbn::imitate::Task;
use dmbn::model::{load_bytes, save_bytes, Network};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};

/// The page's default model with a latent path of `l` values; `active`: its projection drawn
/// at random (as training would leave it) instead of the fresh path's zeros.
fn with_latent(l: usize, active: bool) -> Predictor {
    let device = Device::flex();
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let normalization = shipped.normalization().clone();
    let mut model = shipped
        .model()
        .clone()
        .with_latent_path(l, &device)
        .unwrap();
    if active {
        let Network::Attn(net) = &mut model.network else {
            panic!("attn-sim is attentive");
        };
        let path = net.latent.as_mut().unwrap();
        let dims = path.projection.weight.dims();
        path.projection.weight = Param::from_tensor(Tensor::random(
            dims,
            Distribution::Normal(0.0, 0.5),
            &device,
        ));
    }
    Predictor::new(model, normalization)
}

/// A push's first 30% observed, and every step's time.
fn finish_case() -> (Observations, Vec<f32>, usize) {
    let demo = episode(Action::Move, 515_151, 64).unwrap();
    let steps = Task::Finish.steps(demo.len(), 5).unwrap();
    let observations = Observations::from_sequence(&demo, &steps.observed).unwrap();
    (observations, demo.times(), steps.predicted_from)
}

fn latent(samples: usize, seed: u64) -> Sampling {
    Sampling {
        samples,
        seed,
        method: Method::Latent,
        ..Sampling::default()
    }
}

#[test]
fn a_fresh_latent_path_predicts_as_before() {
    let (observations, times, _) = finish_case();
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let fresh = with_latent(8, false);
    let want = shipped.predict_joints(&observations, &times, 0.5).unwrap();
    let got = fresh.predict_joints(&observations, &times, 0.5).unwrap();
    assert_eq!(want, got, "a path that adds nothing changed the joints");
    // Its futures are the mean, all of them: z moves nothing yet.
    let futures = draw_futures(&fresh, &observations, &times[30..], 0.5, &latent(3, 1)).unwrap();
    let rows = trajectories(&fresh, &futures, &times).unwrap();
    assert!(rows.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn latent_futures_differ_and_are_smooth_and_seeded() {
    let p = with_latent(8, true);
    let (observations, times, from) = finish_case();
    let future = &times[from..];
    let futures = draw_futures(&p, &observations, future, 0.5, &latent(4, 7)).unwrap();
    assert!(
        futures.iter().all(|f| f.drawn.is_empty()),
        "z is drawn, not steps"
    );
    let rows = trajectories(&p, &futures, &times).unwrap();
    let last = times.len() - 1;
    for (i, a) in rows.iter().enumerate() {
        for b in &rows[i + 1..] {
            let gap: f32 = (a[last].iter().zip(&b[last]))
                .map(|(x, y)| (x - y).abs())
                .sum();
            assert!(gap > 1e-3, "two futures end in the same place ({gap})");
        }
    }
    // Seeded, and future s the same whatever S.
    let again = draw_futures(&p, &observations, future, 0.5, &latent(2, 7)).unwrap();
    assert_eq!(
        trajectories(&p, &again, &times).unwrap(),
        rows[..2].to_vec()
    );
    let other = draw_futures(&p, &observations, future, 0.5, &latent(1, 8)).unwrap();
    assert_ne!(trajectories(&p, &other, &times).unwrap()[0], rows[0]);
    // auto draws through the path where there is one, autoregressively where there is none.
    let auto = Sampling {
        method: Method::Auto,
        ..latent(1, 7)
    };
    let through = draw_futures(&p, &observations, future, 0.5, &auto).unwrap();
    assert_eq!(trajectories(&p, &through, &times).unwrap()[0], rows[0]);
    let shipped = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let ar = draw_futures(&shipped, &observations, future, 0.5, &auto).unwrap();
    assert!(!ar[0].drawn.is_empty());
    let refused = draw_futures(&shipped, &observations, future, 0.5, &latent(1, 7)).unwrap_err();
    assert!(refused.to_string().contains("no latent path"), "{refused}");
}

#[test]
fn the_latent_path_survives_the_model_file() {
    let p = with_latent(6, true);
    let bytes = save_bytes(p.model(), p.normalization(), false).unwrap();
    let (model, normalization, config) = load_bytes(&bytes, &Device::flex()).unwrap();
    assert_eq!(config.latent, Some(6));
    let loaded = Predictor::new(model, normalization);
    let (observations, times, from) = finish_case();
    let sampling = latent(2, 3);
    let want = draw_futures(&p, &observations, &times[from..], 0.5, &sampling).unwrap();
    let got = draw_futures(&loaded, &observations, &times[from..], 0.5, &sampling).unwrap();
    assert_eq!(
        trajectories(&p, &want, &times).unwrap(),
        trajectories(&loaded, &got, &times).unwrap()
    );
}

fn exe(name: &str, args: &[&str]) -> std::process::Output {
    let path = match name {
        "train" => env!("CARGO_BIN_EXE_train"),
        _ => env!("CARGO_BIN_EXE_dmbn"),
    };
    Command::new(path).args(args).output().expect("run")
}

#[test]
fn train_latent_adds_a_path_and_logs_its_kl() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (data, run) = (dir.join("data"), dir.join("run"));
    let (d, r) = (data.to_str().unwrap(), run.to_str().unwrap());
    support::simulated_dataset(&data, 0..3, &[Action::Grasp, Action::Move], 5);
    let shipped = support::asset("models/attn-sim.dmbn");
    let init = shipped.to_str().unwrap();
    let two_steps: Vec<&str> = support::TRAIN_TWO_STEPS[2..].to_vec();
    let mut args = vec!["--data", d, "--out", r, "--init", init, "--latent", "4"];
    args.extend(&two_steps);
    let out = exe("train", &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let header = dmbn::model::read_header(&std::fs::read(run.join("model.dmbn")).unwrap()).unwrap();
    assert_eq!(header.config.latent, Some(4));
    let metrics = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    assert!(metrics.lines().all(|l| l.contains("\"kl\":")), "{metrics}");
    // A model with a path samples through it by default (`dmbn sample` records the method).
    let m = run.join("model.dmbn");
    let sample = |model: &str, out: &str, extra: &[&str]| {
        let mut args = vec![
            "sample",
            "--model",
            model,
            "--data",
            d,
            "--sequence",
            "1/move",
        ];
        args.extend(["--observe", "0,10,20", "--samples", "2", "--out", out]);
        args.extend(extra);
        exe("dmbn", &args)
    };
    let out_dir = dir.join("sample");
    let ok = sample(m.to_str().unwrap(), out_dir.to_str().unwrap(), &[]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("samples.json")).unwrap()).unwrap();
    assert_eq!(json["sampling"]["method"], "latent", "{}", json["sampling"]);
    // Refused: a path on a network without attention, another L than the file's, --method
    // latent on a model without one.
    let mut pte: Vec<&str> = vec!["--data", d, "--out", r, "--latent", "4"];
    pte.extend(support::TRAIN_TWO_STEPS);
    let refused = exe("train", &pte);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("latent") && err.contains("attentive"), "{err}");
    let run2 = dir.join("run2");
    let mut other: Vec<&str> = vec!["--data", d, "--out", run2.to_str().unwrap()];
    other.extend(["--init", m.to_str().unwrap(), "--latent", "5"]);
    other.extend(&two_steps);
    let refused = exe("train", &other);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("4 values"),
        "{err}"
    );
    let none = dir.join("none");
    let no_path = sample(init, none.to_str().unwrap(), &["--method", "latent"]);
    let err = String::from_utf8_lossy(&no_path.stderr);
    assert!(
        !no_path.status.success() && err.contains("no latent path"),
        "{err}"
    );
}
