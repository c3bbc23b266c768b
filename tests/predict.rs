//! Inference shared by native and wasm: the golden prediction of the shipped weights (which
//! the wasm tests must reproduce), every bad input as a clear error, and `dmbn predict` end
//! to end.
#![cfg(not(target_arch = "wasm32"))]

#[path = "golden/prediction.rs"]
mod golden_prediction;

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use burn::tensor::Device;
use dmbn::data::{Dataset, DatasetWriter, Normalization, Sequence, JOINTS};
use dmbn::model::{ModelConfig, ModelError, ModelKind};
use dmbn::predict::{heat_map, heat_map_rgb, Observations, Predictor, SequencePrediction};
use dmbn::sim::{episode, Action};
use golden_prediction as golden;

#[test]
fn shipped_weights_reproduce_the_golden_prediction() {
    let predictor = Predictor::from_bytes(golden::MODEL).unwrap();
    let seq = episode(Action::Grasp, golden::SEED, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &golden::OBSERVE).unwrap();
    let prediction = predictor
        .predict(&observations, &seq.times(), golden::BLEND)
        .unwrap();
    assert_eq!(prediction.len(), seq.len());
    let sample = golden::sample(&prediction);
    if std::env::var_os("DMBN_BLESS").is_some() {
        assert!(
            std::env::var_os("CI").is_none(),
            "DMBN_BLESS is refused under CI"
        );
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/prediction.json");
        std::fs::write(&path, serde_json::to_string(&sample).unwrap()).unwrap();
        return;
    }
    let (diff, at) = golden::max_diff(&sample, &golden::expected());
    assert!(
        diff < 1e-5,
        "differs from tests/golden/prediction.json by {diff} at {at} (re-bless with DMBN_BLESS=1 after changing the weights)"
    );
}

/// Every way to make a predictor freezes its kernels (the page and `dmbn predict` load from
/// bytes or a file; an unfrozen model compares all its weights on every call).
#[test]
fn every_predictor_has_frozen_kernels() {
    let from_bytes = Predictor::from_bytes(golden::MODEL).unwrap();
    assert!(from_bytes.model().kernels_frozen());
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("model.dmbn");
    std::fs::write(&path, golden::MODEL).unwrap();
    assert!(Predictor::load(&path).unwrap().model().kernels_frozen());
    let expecting = Predictor::from_bytes_expecting(golden::MODEL, None, Some(64)).unwrap();
    assert!(expecting.model().kernels_frozen());
    let device = Device::flex();
    let model = ModelConfig::new(ModelKind::Pte).init(&device).unwrap();
    assert!(!model.kernels_frozen());
    assert!(Predictor::new(model, Normalization::identity(JOINTS))
        .model()
        .kernels_frozen());
}

#[test]
fn encoding_once_and_decoding_in_chunks_equals_one_call() {
    let predictor = Predictor::from_bytes(golden::MODEL).unwrap();
    let seq = episode(Action::Move, 3, 64).unwrap();
    let observations = Observations::from_sequence(&seq, &[5, 10]).unwrap();
    let times = seq.times();
    let whole = predictor.predict(&observations, &times, 1.0).unwrap();
    let r = predictor.encode(&observations, 1.0).unwrap();
    let one = predictor.decode(&r, &times[7..8]).unwrap();
    let n = 64 * 64 * 3;
    let diff = one
        .image_mean
        .iter()
        .zip(&whole.image_mean[7 * n..8 * n])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(diff < 1e-5, "decoding one target alone differs by {diff}");
    let joints = one
        .joint_mean
        .iter()
        .zip(&whole.joint_mean[7 * 7..8 * 7])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(joints < 1e-5, "joints differ by {joints}");
}

/// The largest difference between two predictions' values, against their scale (at least 1).
fn relative_diff(a: &SequencePrediction, b: &SequencePrediction) -> f32 {
    let pairs = [
        (&a.image_mean, &b.image_mean),
        (&a.image_sigma, &b.image_sigma),
        (&a.joint_mean, &b.joint_mean),
        (&a.joint_sigma, &b.joint_sigma),
    ];
    pairs
        .iter()
        .map(|(x, y)| {
            assert_eq!(x.len(), y.len());
            let scale = x.iter().fold(1.0f32, |m, v| m.max(v.abs()));
            let diff = x.iter().zip(y.iter()).map(|(p, q)| (p - q).abs());
            diff.fold(0.0, f32::max) / scale
        })
        .fold(0.0, f32::max)
}

/// The page's live forecast encodes each observation once and joins the sets: for every
/// shipped kind, the joined (and the cut) sets predict what the observations encoded together
/// do, at every blend.
#[test]
fn joined_and_selected_encodings_predict_as_the_observations_encoded_together() {
    let seq = episode(Action::Grasp, 5, 64).unwrap();
    let obs = |steps: &[usize]| Observations::from_sequence(&seq, steps).unwrap();
    let targets: Vec<f32> = seq.times().into_iter().step_by(6).collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models");
    for file in ["dmbn-sim.dmbn", "pte-sim.dmbn", "attn-sim.dmbn"] {
        let predictor = Predictor::load(dir.join(file)).unwrap();
        let (a, b) = ([0, 10, 20], [31, 45]);
        let joined = predictor
            .encode_contexts(&obs(&a))
            .unwrap()
            .cat(&predictor.encode_contexts(&obs(&b)).unwrap())
            .unwrap();
        assert_eq!(joined.len(), 5);
        let every = obs(&[0, 10, 20, 31, 45]);
        let selected = joined.select(&[4, 0, 2]).unwrap();
        for blend in [0.0, 0.5, 1.0] {
            let cached = predictor.represent(&joined, blend).unwrap();
            let cached = predictor.decode(&cached, &targets).unwrap();
            let whole = predictor.predict(&every, &targets, blend).unwrap();
            let diff = relative_diff(&cached, &whole);
            assert!(
                diff < 1e-5,
                "{file} c = {blend}: joined sets differ by {diff}"
            );
            let cut = predictor.represent(&selected, blend).unwrap();
            let cut = predictor.decode(&cut, &targets).unwrap();
            let whole = predictor
                .predict(&obs(&[45, 0, 20]), &targets, blend)
                .unwrap();
            let diff = relative_diff(&cut, &whole);
            assert!(
                diff < 1e-5,
                "{file} c = {blend}: a selection differs by {diff}"
            );
        }
        let err = message(joined.select(&[]).unwrap_err());
        assert!(err.contains("at least one context"), "{err}");
        let err = message(joined.select(&[1, 5]).unwrap_err());
        assert!(
            err.contains("index 5") && err.contains("5 contexts"),
            "{err}"
        );
        let err = message(predictor.represent(&joined, 1.5).unwrap_err());
        assert!(err.contains("blend"), "{err}");
    }
    // Another kind's encodings are refused, to join or to represent.
    let dmbn = Predictor::load(dir.join("dmbn-sim.dmbn")).unwrap();
    let pte = Predictor::load(dir.join("pte-sim.dmbn")).unwrap();
    let (d, p) = (
        dmbn.encode_contexts(&obs(&[0])).unwrap(),
        pte.encode_contexts(&obs(&[5])).unwrap(),
    );
    let err = message(d.cat(&p).unwrap_err());
    assert!(
        err.contains("dmbn model") && err.contains("pte model"),
        "{err}"
    );
    let err = message(pte.represent(&d, 0.5).unwrap_err());
    assert!(err.contains("encoded by a dmbn model"), "{err}");
}

fn fresh(kind: ModelKind, image_size: usize) -> Predictor {
    let device = Device::flex();
    let model = ModelConfig::new(kind)
        .with_image_size(image_size)
        .init(&device)
        .unwrap();
    Predictor::new(model, Normalization::identity(JOINTS))
}

fn message(err: ModelError) -> String {
    err.to_string()
}

#[test]
fn bad_inference_input_is_a_clear_error() {
    let predictor = fresh(ModelKind::Pte, 64);
    let seq = episode(Action::Grasp, 1, 64).unwrap();
    let good = Observations::from_sequence(&seq, &[0, 10]).unwrap();
    let times = [0.0, 0.5];

    let mut small = good.clone();
    small.frames.truncate(2 * 32 * 32 * 3);
    let err = message(predictor.predict(&small, &times, 0.5).unwrap_err());
    assert!(err.contains("frames") && err.contains("64×64×3"), "{err}");

    let mut other_size = good.clone();
    other_size.image_size = 128;
    let err = message(predictor.predict(&other_size, &times, 0.5).unwrap_err());
    assert!(err.contains("128x128") && err.contains("64x64"), "{err}");

    let empty = Observations {
        image_size: 64,
        frames: vec![],
        joints: vec![],
        times: vec![],
    };
    let err = message(predictor.predict(&empty, &times, 0.5).unwrap_err());
    assert!(err.contains("at least one observed step"), "{err}");

    for blend in [1.5, -0.1, f32::NAN] {
        let err = message(predictor.predict(&good, &times, blend).unwrap_err());
        assert!(
            err.contains("blend") && err.contains("[0, 1]"),
            "{blend}: {err}"
        );
    }

    let mut joints = good.clone();
    joints.joints.pop();
    let err = message(predictor.predict(&joints, &times, 0.5).unwrap_err());
    assert!(
        err.contains("joints") && err.contains("expected 2 steps × 7 = 14"),
        "{err}"
    );

    let mut late = good.clone();
    late.times[1] = 1.5;
    let err = message(predictor.predict(&late, &times, 0.5).unwrap_err());
    assert!(err.contains("times") && err.contains("[0, 1]"), "{err}");

    let err = message(
        predictor
            .predict(&good, &[0.1, f32::INFINITY], 0.5)
            .unwrap_err(),
    );
    assert!(err.contains("target_times"), "{err}");

    let err = message(Observations::from_sequence(&seq, &[0, 999]).unwrap_err());
    assert!(err.contains("999"), "{err}");

    // No target times: an empty prediction, not an error.
    assert!(predictor.predict(&good, &[], 0.5).unwrap().is_empty());
}

#[test]
fn bad_model_files_are_clear_errors() {
    let bytes = golden::MODEL;
    let err = message(Predictor::from_bytes(&bytes[..bytes.len() / 2]).unwrap_err());
    assert!(err.contains("truncated"), "{err}");
    let err = message(Predictor::from_bytes(b"\x89PNG\r\n\x1a\n0000000000").unwrap_err());
    assert!(err.contains("not a dmbn model file"), "{err}");
    let err = message(Predictor::from_bytes(&[]).unwrap_err());
    assert!(!err.is_empty());
    let err =
        message(Predictor::from_bytes_expecting(bytes, Some(ModelKind::Pte), None).unwrap_err());
    assert!(err.contains("pte") && err.contains("dmbn"), "{err}");
    let err = message(Predictor::from_bytes_expecting(bytes, None, Some(128)).unwrap_err());
    assert!(err.contains("128"), "{err}");
    let err = message(Predictor::load("/nonexistent/model.dmbn").unwrap_err());
    assert!(err.contains("/nonexistent/model.dmbn"), "{err}");
    // A bad file read from a path says which file.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("half.dmbn");
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let err = message(Predictor::load(&path).unwrap_err());
    assert!(
        err.contains(&*path.to_string_lossy()) && err.contains("truncated"),
        "{err}"
    );
}

fn dmbn(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(args)
        .output()
        .expect("run dmbn")
}

/// `dmbn predict --model model` on `seq`, written as sequence 0/grasp of a dataset in
/// `dir/data`, observed at steps 0, 20 and 40 (`golden::OBSERVE`) with blend 0.5 (the
/// default, `golden::BLEND`), into `dir/out`: the data and output folders and the run.
fn predict_grasp(dir: &Path, model: &Path, seq: &Sequence) -> (PathBuf, PathBuf, Output) {
    let (data, out) = (dir.join("data"), dir.join("out"));
    let mut writer = DatasetWriter::create(&data).unwrap();
    writer.write(0, "grasp", seq).unwrap();
    writer.finish().unwrap();
    let path = |p: &Path| p.to_str().unwrap().to_string();
    let run = dmbn(&[
        "predict",
        "--model",
        &path(model),
        "--data",
        &path(&data),
        "--sequence",
        "0/grasp",
        "--observe",
        "0,20,40",
        "--out",
        &path(&out),
    ]);
    (data, out, run)
}

#[test]
fn dmbn_predict_writes_figures_and_scores() {
    let tmp = tempfile::tempdir().unwrap();
    let model_path = tmp.path().join("model.dmbn");
    let device = Device::flex();
    let model = ModelConfig::new(ModelKind::Dmbn).init(&device).unwrap();
    support::save_model(&model_path, &model, &Normalization::identity(JOINTS), true);
    let seq = episode(Action::Grasp, 11, 64).unwrap();
    let (data, out, run) = predict_grasp(tmp.path(), &model_path, &seq);
    let (m, d, o) = (
        model_path.to_str().unwrap(),
        data.to_str().unwrap(),
        out.to_str().unwrap(),
    );

    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("image: MSE") && stdout.contains("NLL"),
        "{stdout}"
    );
    let steps = seq.len();
    for dir in ["mean", "sigma", "truth"] {
        assert_eq!(
            std::fs::read_dir(out.join(dir)).unwrap().count(),
            steps,
            "{dir}"
        );
        let frame = image::open(out.join(dir).join("0.png")).unwrap();
        assert_eq!((frame.width(), frame.height()), (64, 64));
    }
    assert!(image::open(out.join("joints.png")).unwrap().width() > 100);
    let scores: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("scores.json")).unwrap()).unwrap();
    assert!(scores["scores"]["image_mse"].as_f64().unwrap() > 0.0);
    assert_eq!(scores["observed"], serde_json::json!([0, 20, 40]));

    let fails = |args: &[&str], needle: &str| {
        let run = dmbn(args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success() && stderr.contains(needle),
            "{args:?}: {stderr}"
        );
    };
    fails(
        &[
            "predict",
            "--model",
            m,
            "--data",
            d,
            "--sequence",
            "0/grasp",
            "--observe",
            "0",
            "--blend",
            "2",
            "--out",
            o,
        ],
        "[0, 1]",
    );
    fails(
        &[
            "predict",
            "--model",
            m,
            "--data",
            d,
            "--sequence",
            "5/grasp",
            "--observe",
            "0",
            "--out",
            o,
        ],
        "no sequence 5/grasp",
    );
    fails(
        &[
            "predict",
            "--model",
            m,
            "--data",
            d,
            "--sequence",
            "grasp",
            "--observe",
            "0",
            "--out",
            o,
        ],
        "ID/ACTION",
    );
    fails(
        &[
            "predict",
            "--model",
            m,
            "--data",
            d,
            "--sequence",
            "0/grasp",
            "--observe",
            "0,500",
            "--out",
            o,
        ],
        "500",
    );
    fails(
        &[
            "predict",
            "--model",
            d,
            "--data",
            d,
            "--sequence",
            "0/grasp",
            "--observe",
            "0",
            "--out",
            o,
        ],
        d,
    );
}

/// The σ heat maps the page draws for a prediction are the images `dmbn predict` writes for
/// it: the same scale (the largest pixel σ, which the page takes over the chunks its workers
/// decode, 10 steps each) and the same ramp (`heat_map`, the page's `heatMap`).
#[test]
fn the_page_and_dmbn_predict_draw_the_same_sigma_heat_maps() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model.dmbn");
    std::fs::write(&model, golden::MODEL).unwrap();
    let (data, out, run) = predict_grasp(
        tmp.path(),
        &model,
        &episode(Action::Grasp, golden::SEED, 64).unwrap(),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // The sequence as `dmbn predict` reads it.
    let data = Dataset::open(&data).unwrap();
    let seq = data.read(data.find(0, "grasp").unwrap(), None).unwrap();

    let predictor = Predictor::from_bytes(golden::MODEL).unwrap();
    let observations = Observations::from_sequence(&seq, &golden::OBSERVE).unwrap();
    let whole = predictor
        .predict(&observations, &seq.times(), golden::BLEND)
        .unwrap();
    // The page: www/worker.js decodes chunks, www/prediction.js keeps the largest σ so far,
    // www/draw.js colours each step's pixel σ with wasm's `heatMap`.
    let encoding = predictor.encode(&observations, golden::BLEND).unwrap();
    let chunks: Vec<SequencePrediction> = seq
        .times()
        .chunks(10)
        .map(|times| predictor.decode(&encoding, times).unwrap())
        .collect();
    let max = whole.max_image_sigma();
    let maxima = chunks.iter().map(SequencePrediction::max_image_sigma);
    let scale = golden::page_scale(maxima, max, 1e-5);
    let sigma: Vec<f32> = chunks.iter().flat_map(|c| c.pixel_sigma()).collect();
    let px = 64 * 64;
    let mut yellow = 0;
    for k in 0..seq.len() {
        let written = image::open(out.join("sigma").join(format!("{k}.png")))
            .unwrap()
            .into_rgb8()
            .into_raw();
        yellow += written
            .chunks_exact(3)
            .filter(|&rgb| rgb == heat_map_rgb(1.0))
            .count();
        assert_eq!(written, whole.sigma_map(k, max), "sigma/{k}.png");
        let page = heat_map(&sigma[k * px..(k + 1) * px], scale);
        let worst = page
            .iter()
            .zip(&written)
            .map(|(&a, &b)| a.abs_diff(b))
            .max();
        assert!(
            worst <= Some(1),
            "step {k}: the page's heat map and sigma/{k}.png differ by {worst:?}"
        );
    }
    // The scale is the largest σ shown: the most uncertain pixel is full yellow.
    assert!(yellow > 0, "no pixel of sigma/*.png is full yellow");
}
