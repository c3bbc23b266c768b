//! Weights for PyTorch: `dmbn export` / `dmbn import` (safetensors) round trips, the names and
//! layouts PyTorch sees, clear errors for bad files, and — wherever torch is installed — the
//! PyTorch twin (python/dmbn_torch/) predicting what `dmbn predict` does. Native only.
#![cfg(not(target_arch = "wasm32"))]

#[path = "golden/prediction.rs"]
mod golden;
mod support;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use burn::tensor::Device;
use dmbn::model::{
    export_safetensors, import_safetensors, load_bytes, read_header, with_joint_sigma_scale,
    JointSigmaScale, ModelError,
};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{Action, Arm};
use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensors};

/// The simulator arm whose joint count the model file `bytes` reads.
fn arm_of(bytes: &[u8]) -> Arm {
    Arm::of_width(read_header(bytes).unwrap().config.joint_count()).unwrap()
}

/// Every shipped model file: what users export.
fn shipped() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(support::asset("models"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "dmbn"))
        .collect();
    files.sort();
    files
}

/// A simulated 64-px sequence and observations at a few of its steps.
fn observations() -> (Observations, Vec<f32>) {
    observations_of(Arm::Ur5)
}

/// [`observations`] of `arm`'s episode: for a model of that arm's joint count.
fn observations_of(arm: Arm) -> (Observations, Vec<f32>) {
    let episode = dmbn::sim::episode_with_arm(arm, Action::Grasp, 3, 64).unwrap();
    let steps = [0, 9, 23, episode.len() - 1];
    (
        Observations::from_sequence(&episode, &steps).unwrap(),
        episode.times(),
    )
}

#[test]
fn export_then_import_predicts_exactly_as_the_shipped_model() {
    for path in shipped() {
        let bytes = std::fs::read(&path).unwrap();
        let (obs, times) = observations_of(arm_of(&bytes));
        let exported = export_safetensors(&bytes, false).unwrap();
        let imported = import_safetensors(&exported, false).unwrap();
        let header = read_header(&bytes).unwrap();
        let back = read_header(&imported).unwrap();
        assert_eq!(back.config, header.config, "{}", path.display());
        assert_eq!(back.normalization, header.normalization);
        // The joint correlation too, its regions' centres and phases with it.
        assert_eq!(
            back.joint_correlation().unwrap(),
            header.joint_correlation().unwrap(),
            "{}",
            path.display()
        );
        for blend in [0.0, 0.5, 1.0] {
            let want = Predictor::from_bytes(&bytes)
                .unwrap()
                .predict(&obs, &times, blend)
                .unwrap();
            let got = Predictor::from_bytes(&imported)
                .unwrap()
                .predict(&obs, &times, blend)
                .unwrap();
            assert_eq!(got, want, "{} blend {blend}", path.display());
        }
    }
}

/// A calibrated file's joint σ scale goes to PyTorch in the metadata and comes back.
#[test]
fn the_joint_sigma_scale_survives_export_and_import() {
    let bytes = std::fs::read(support::asset("models/dmbn-sim.dmbn")).unwrap();
    let scale = JointSigmaScale {
        between: 1.3,
        forecast: Some(0.7),
    };
    let scaled = with_joint_sigma_scale(&bytes, scale).unwrap();
    let back = import_safetensors(&export_safetensors(&scaled, false).unwrap(), false).unwrap();
    assert_eq!(read_header(&back).unwrap().joint_sigma_scales(), scale);
    // A file without a scale (the paper-recipe DMBN is shipped uncalibrated) gets none.
    let bytes = std::fs::read(support::asset("models/dmbn-paper-2020.dmbn")).unwrap();
    assert_eq!(read_header(&bytes).unwrap().joint_sigma_scale, None);
    let plain = import_safetensors(&export_safetensors(&bytes, false).unwrap(), false).unwrap();
    assert_eq!(read_header(&plain).unwrap().joint_sigma_scale, None);
    assert_eq!(
        read_header(&plain).unwrap().forecast_joint_sigma_scale,
        None
    );
}

#[test]
fn export_uses_pytorch_names_layouts_and_metadata() {
    let path = support::asset("models/attn-sim.dmbn");
    let bytes = std::fs::read(&path).unwrap();
    let exported = export_safetensors(&bytes, false).unwrap();
    let file = SafeTensors::deserialize(&exported).unwrap();
    let shape = |name: &str| file.tensor(name).unwrap().shape().to_vec();
    // Linear [out, in], Conv2d [out, in, kh, kw], LayerNorm weight/bias.
    assert_eq!(shape("decoder.shared.weight"), [1024, 128]);
    assert_eq!(shape("joint_encoder.layers.0.weight"), [32, 7]);
    // (The shipped file's image encoder has half the original's filters: 16, not 32.)
    assert_eq!(shape("image_encoder.convs.0.weight"), [16, 3, 3, 3]);
    assert_eq!(shape("image_projection.norm.weight"), [128]);
    assert_eq!(shape("image_projection.norm.bias"), [128]);
    assert_eq!(shape("image_attention.query.weight"), [128, 128]);
    assert_eq!(shape("observed"), [2, 128]);
    assert!(file.names().iter().all(|n| !n.starts_with("network")));
    assert!(file
        .tensors()
        .iter()
        .all(|(_, view)| view.dtype() == Dtype::F32));
    // The transposed weights hold the same values: y = x·Wᵀ in PyTorch is x·W in burn.
    let (model, normalization, config) = load_bytes(&bytes, &Device::flex()).unwrap();
    let dmbn::model::Network::Attn(net) = &model.network else {
        panic!("an attentive model")
    };
    let burn: Vec<f32> = net
        .decoder
        .shared
        .weight
        .val()
        .into_data()
        .try_to_vec()
        .unwrap();
    let name = "decoder.shared.weight";
    let torch = support::f32_values(name, &file.tensor(name).unwrap());
    assert_eq!(torch[5 * 128 + 3], burn[3 * 1024 + 5]);
    let header = dmbn::model::safetensors_file::read_metadata(&exported).unwrap();
    assert_eq!(header.config, config);
    assert_eq!(header.normalization, normalization);

    let half = export_safetensors(&bytes, true).unwrap();
    assert!(half.len() < exported.len() * 6 / 10);
    let file = SafeTensors::deserialize(&half).unwrap();
    assert!(file
        .tensors()
        .iter()
        .all(|(_, view)| view.dtype() == Dtype::F16));
    // An f16 export imports (as f32 or f16) and predicts close to the original.
    let (obs, times) = observations();
    let want = Predictor::from_bytes(&bytes)
        .unwrap()
        .predict(&obs, &times, 0.5)
        .unwrap();
    for half_file in [false, true] {
        let got = Predictor::from_bytes(&import_safetensors(&half, half_file).unwrap())
            .unwrap()
            .predict(&obs, &times, 0.5)
            .unwrap();
        let diff = got
            .joint_mean
            .iter()
            .zip(&want.joint_mean)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        assert!(diff < 0.05, "f16 joints differ by {diff}");
    }
}

/// A tensor of a safetensors file: name, dtype, shape, bytes.
type Entry = (String, Dtype, Vec<usize>, Vec<u8>);

/// A safetensors file of `tensors` (name, dtype, shape, bytes) with `metadata`.
fn write(tensors: &[Entry], metadata: Option<&str>) -> Vec<u8> {
    let views: Vec<(&str, TensorView)> = tensors
        .iter()
        .map(|(n, d, s, b)| (n.as_str(), TensorView::new(*d, s.clone(), b).unwrap()))
        .collect();
    let metadata = metadata.map(|m| HashMap::from([("dmbn".to_string(), m.to_string())]));
    safetensors::serialize(views, metadata).unwrap()
}

/// The tensors and metadata of an exported file, to be altered.
fn parts(exported: &[u8]) -> (Vec<Entry>, String) {
    let file = SafeTensors::deserialize(exported).unwrap();
    let tensors = file
        .tensors()
        .into_iter()
        .map(|(n, v)| (n, v.dtype(), v.shape().to_vec(), v.data().to_vec()))
        .collect();
    let metadata = dmbn::model::safetensors_file::read_metadata(exported).unwrap();
    (tensors, serde_json::to_string(&metadata).unwrap())
}

fn import_err(bytes: &[u8]) -> String {
    match import_safetensors(bytes, false) {
        Err(e @ ModelError::Safetensors(_)) | Err(e @ ModelError::Config { .. }) => e.to_string(),
        Err(e) => panic!("unexpected error kind: {e}"),
        Ok(_) => panic!("a bad file imported"),
    }
}

#[test]
fn bad_files_give_clear_errors() {
    let bytes = std::fs::read(support::asset("models/dmbn-sim.dmbn")).unwrap();
    let exported = export_safetensors(&bytes, false).unwrap();
    let (tensors, metadata) = parts(&exported);

    let err = import_err(&bytes);
    assert!(err.contains("a dmbn model file, not safetensors"), "{err}");
    let err = import_err(b"not a safetensors file at all");
    assert!(err.contains("not a readable safetensors file"), "{err}");
    let err = import_err(&exported[..exported.len() / 2]);
    assert!(err.contains("not a readable safetensors file"), "{err}");

    let err = import_err(&write(&tensors, None));
    assert!(err.contains("no `dmbn` metadata"), "{err}");
    let err = import_err(&write(&tensors, Some("{\"config\": 3}")));
    assert!(err.contains("bad `dmbn` metadata"), "{err}");

    // Another kind's tensors: the first one the pte model needs is named.
    let pte = metadata.replace("\"kind\":\"dmbn\"", "\"kind\":\"pte\"");
    let err = import_err(&write(&tensors, Some(&pte)));
    assert!(
        err.contains("is missing") && err.contains("pte model"),
        "{err}"
    );

    // A wrong shape: which tensor, what was expected, what was found.
    let mut wrong = tensors.clone();
    let i = wrong
        .iter()
        .position(|t| t.0 == "decoder.shared.weight")
        .unwrap();
    wrong[i].2 = vec![1024, 129 - 1];
    wrong[i].3.truncate(1024 * 128 * 4);
    let err = import_err(&write(&wrong, Some(&metadata)));
    assert!(
        err.contains("`decoder.shared.weight`")
            && err.contains("[1024, 128]")
            && err.contains("[1024, 129]"),
        "{err}"
    );

    // A tensor the model does not have.
    let mut extra = tensors.clone();
    extra.push(("head.weight".into(), Dtype::F32, vec![1], vec![0; 4]));
    let err = import_err(&write(&extra, Some(&metadata)));
    assert!(err.contains("head.weight"), "{err}");

    // Integers where floats belong.
    let mut ints = tensors.clone();
    ints[0].1 = Dtype::I32;
    let err = import_err(&write(&ints, Some(&metadata)));
    assert!(err.contains("I32") && err.contains(&ints[0].0), "{err}");

    // A bad config in the metadata names its field.
    let bad = metadata.replace("\"image_size\":64", "\"image_size\":96");
    let err = import_err(&write(&tensors, Some(&bad)));
    assert!(err.contains("image_size"), "{err}");
}

#[test]
fn the_cli_exports_and_imports_and_names_the_file_in_errors() {
    let dir = tempfile::tempdir().unwrap();
    let st = dir.path().join("pte.safetensors");
    let back = dir.path().join("pte.dmbn");
    let model = support::asset("models/pte-sim.dmbn");
    let run = |args: &[&Path]| {
        Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[
        "export".as_ref(),
        "--model".as_ref(),
        &model,
        "--out".as_ref(),
        &st,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(&[
        "import".as_ref(),
        "--from".as_ref(),
        &st,
        "--out".as_ref(),
        &back,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (obs, times) = observations();
    let want = Predictor::load(&model).unwrap().predict(&obs, &times, 0.5);
    let got = Predictor::load(&back).unwrap().predict(&obs, &times, 0.5);
    assert_eq!(got.unwrap(), want.unwrap());
    // Importing a model file (not safetensors) fails, naming the file; nothing is written.
    let bad = dir.path().join("bad.dmbn");
    let out = run(&[
        "import".as_ref(),
        "--from".as_ref(),
        &model,
        "--out".as_ref(),
        &bad,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("pte-sim.dmbn"),
        "{err}"
    );
    assert!(err.contains("not safetensors"), "{err}");
    assert!(!bad.exists());
}

#[test]
fn the_pytorch_twin_predicts_what_dmbn_predict_does() {
    let Some(python) = support::python_with_torch() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    // Sequence 0 is the golden prediction's episode; the second arm's for its models.
    support::simulated_dataset(&data, [0], &[Action::Grasp], golden::SEED);
    let panda_data = dir.path().join("panda");
    support::simulated_arm_dataset(&panda_data, Arm::Panda, [0], &[Action::Grasp], golden::SEED);
    let observe = golden::OBSERVE.map(|k| k.to_string()).join(",");
    let dmbn = |args: &[&std::ffi::OsStr]| {
        let out = Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    // Every shipped file, and one with a joint σ scale (`dmbn calibrate`), which the twin
    // must apply as the Rust predictor does.
    let calibrated = dir.path().join("dmbn-sim-calibrated.dmbn");
    let bytes = std::fs::read(support::asset("models/dmbn-sim.dmbn")).unwrap();
    let scale = JointSigmaScale {
        between: 1.3,
        forecast: Some(0.7),
    };
    std::fs::write(&calibrated, with_joint_sigma_scale(&bytes, scale).unwrap()).unwrap();
    for model in shipped().into_iter().chain([calibrated]) {
        let name = model.file_stem().unwrap().to_string_lossy().into_owned();
        let data = match arm_of(&std::fs::read(&model).unwrap()) {
            Arm::Ur5 => &data,
            Arm::Panda => &panda_data,
        };
        let st = dir.path().join(format!("{name}.safetensors"));
        dmbn(&[
            "export".as_ref(),
            "--model".as_ref(),
            model.as_ref(),
            "--out".as_ref(),
            st.as_ref(),
        ]);
        for blend in ["0.5", "1", "0"] {
            let out = dir.path().join(format!("{name}-{blend}"));
            dmbn(&[
                "predict".as_ref(),
                "--model".as_ref(),
                model.as_ref(),
                "--data".as_ref(),
                data.as_ref(),
                "--sequence".as_ref(),
                "0/grasp".as_ref(),
                "--observe".as_ref(),
                observe.as_ref(),
                "--blend".as_ref(),
                blend.as_ref(),
                "--out".as_ref(),
                out.as_ref(),
                "--arrays".as_ref(),
            ]);
            let twin = out.join("twin.safetensors");
            let check = support::twin(&python)
                .args(["-m", "dmbn_torch", "check"])
                .arg(&st)
                .arg(out.join("prediction.safetensors"))
                .args(["--tolerance", "1e-4", "--out"])
                .arg(&twin)
                .output()
                .unwrap();
            let report = String::from_utf8_lossy(&check.stdout);
            println!("{name} blend {blend}: {report}");
            assert!(
                check.status.success(),
                "{name} blend {blend}: {report}{}",
                String::from_utf8_lossy(&check.stderr)
            );
            if name == "dmbn-sim" && blend == "0.5" {
                // The golden prediction (written by the code under test) against the twin: an
                // independent reference.
                let bytes = std::fs::read(&twin).unwrap();
                let file = SafeTensors::deserialize(&bytes).unwrap();
                let array = |name: &str| support::f32_values(name, &file.tensor(name).unwrap());
                let prediction = dmbn::predict::SequencePrediction {
                    image_size: 64,
                    joints: dmbn::data::JOINTS,
                    times: Vec::new(),
                    image_mean: array("image_mean"),
                    image_sigma: array("image_sigma"),
                    joint_mean: array("joint_mean"),
                    joint_sigma: array("joint_sigma"),
                };
                let (diff, at) =
                    golden::max_diff(&golden::sample(&prediction), &golden::expected());
                assert!(
                    diff < 1e-4,
                    "the twin differs from tests/golden/prediction.json by {diff} at {at}"
                );
            }
        }
    }
}

/// Weights changed in PyTorch come back: the twin loads an exported file, shifts one tensor
/// (the joint mean head's bias, +0.5 in normalised units), `save`s it, and `dmbn import` gives
/// a model file whose joint means moved by exactly 0.5 σ of the normalisation and nothing else.
#[test]
fn the_pytorch_twin_saves_what_dmbn_import_reads() {
    let Some(python) = support::python_with_torch() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (exported, trained, back) = (
        dir.path().join("dmbn.safetensors"),
        dir.path().join("trained.safetensors"),
        dir.path().join("trained.dmbn"),
    );
    let original = std::fs::read(support::asset("models/dmbn-sim.dmbn")).unwrap();
    std::fs::write(&exported, export_safetensors(&original, false).unwrap()).unwrap();
    let script = "import sys, torch\n\
        import dmbn_torch\n\
        model = dmbn_torch.load(sys.argv[1])\n\
        with torch.no_grad():\n    model.network.decoder.joint.mean.bias.add_(0.5)\n\
        dmbn_torch.save(model, sys.argv[2])\n";
    for command in [
        support::twin(&python)
            .args(["-c", script])
            .arg(&exported)
            .arg(&trained),
        Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .arg("import")
            .arg("--from")
            .arg(&trained)
            .arg("--out")
            .arg(&back),
    ] {
        let out = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
    }

    let (obs, times) = observations();
    let predict = |bytes: &[u8]| {
        Predictor::from_bytes(bytes)
            .unwrap()
            .predict(&obs, &times, 0.5)
            .unwrap()
    };
    let imported = std::fs::read(&back).unwrap();
    let (before, after) = (predict(&original), predict(&imported));
    assert_eq!(
        after.image_mean, before.image_mean,
        "the frames are untouched"
    );
    assert_eq!(after.joint_sigma, before.joint_sigma);
    let std = read_header(&original).unwrap().normalization.std;
    for (i, (a, b)) in after.joint_mean.iter().zip(&before.joint_mean).enumerate() {
        let moved = (a - b) / std[i % 7];
        assert!(
            (moved - 0.5).abs() < 1e-4,
            "joint {i}: moved {moved} σ, expected 0.5"
        );
    }
}
