//! Another robot's data: 8 joint values a step (a 7-joint arm and its gripper), no object or
//! end-effector files, non-square frames, a second camera and a `dataset.json` naming the
//! joints. `inspect`, `train`, `predict` and `score` take it through the same commands as the
//! original robot's; a model of another joint count, bad column counts and a missing camera
//! are refused with messages naming the file and both counts; `imitate` says it needs the
//! simulator's data.
#![cfg(not(target_arch = "wasm32"))]

use std::path::Path;
use std::process::{Command, Output};

use dmbn::data::{read_sequence_from, Dataset, DatasetMeta, Disk};
use dmbn::model::read_header;

const D: usize = 8;
const NAMES: [&str; D] = [
    "shoulder",
    "upper_arm",
    "elbow",
    "forearm",
    "wrist_1",
    "wrist_2",
    "wrist_3",
    "gripper",
];

fn dmbn(bin: &str, args: &[&str]) -> Output {
    Command::new(bin).args(args).output().unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Joint `j` of sequence `id` at step `k` of `t`: smooth, different per joint and sequence.
fn joint(id: u32, j: usize, k: usize, t: usize) -> f32 {
    let phase = k as f32 / (t - 1) as f32;
    (0.3 + 0.1 * j as f32) * (phase * (1.0 + j as f32 * 0.3) + id as f32 * 0.2).sin()
}

/// A frame of `w × h`: a bar whose place follows the phase, on a background per camera.
fn frame(w: u32, h: u32, phase: f32, shade: u8) -> image::RgbImage {
    let x0 = (phase * (w - 8) as f32) as u32;
    image::RgbImage::from_fn(w, h, |x, y| {
        if (x0..x0 + 8).contains(&x) && y > h / 4 {
            image::Rgb([220, 60, 40])
        } else {
            image::Rgb([shade, shade, 200])
        }
    })
}

/// `ids` sequences of `t` steps of action `reach`: `joint_<id>.txt` with 8 columns, 48 × 32
/// frames of the default camera and 40 × 40 of the `wrist` camera, no object or endpoint file,
/// and `dataset.json` naming the joints.
fn robot_dataset(root: &Path, ids: u32, t: usize) {
    for id in 0..ids {
        let dir = root.join(id.to_string()).join("reach");
        std::fs::create_dir_all(dir.join("wrist")).unwrap();
        let mut rows = String::new();
        for k in 0..t {
            let row: Vec<String> = (0..D).map(|j| joint(id, j, k, t).to_string()).collect();
            rows += &(row.join(" ") + "\n");
            let phase = k as f32 / (t - 1) as f32;
            frame(48, 32, phase, 30)
                .save(dir.join(format!("{k}.png")))
                .unwrap();
            frame(40, 40, 1.0 - phase, 90)
                .save(dir.join("wrist").join(format!("{k}.png")))
                .unwrap();
        }
        std::fs::write(dir.join(format!("joint_{id}.txt")), rows).unwrap();
    }
    let meta = DatasetMeta {
        joint_names: Some(NAMES.map(String::from).to_vec()),
        cameras: Some(vec!["front".into(), "wrist".into()]),
        fps: Some(10.0),
        source: None,
    };
    std::fs::write(
        root.join("dataset.json"),
        serde_json::to_vec(&meta).unwrap(),
    )
    .unwrap();
}

#[test]
fn the_shape_comes_from_the_data() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("robot");
    robot_dataset(&data, 4, 14);
    let dataset = Dataset::open(&data).unwrap();
    let (width, names) = dataset.joint_width(&Disk).unwrap();
    assert_eq!(width, D);
    assert_eq!(names.unwrap()[0], "shoulder");
    let first = &dataset.sequences()[0];
    let seq = dataset.read(first, Some(64)).unwrap();
    assert_eq!((seq.joints.width(), seq.len(), seq.image_size), (D, 14, 64));
    assert!(seq.object.is_none() && seq.endpoint.is_none());
    let wrist = read_sequence_from(&Disk, &first.dir, first.id, Some("wrist"), Some(64)).unwrap();
    assert_ne!(
        wrist.frames, seq.frames,
        "the wrist camera's frames, not the default's"
    );
    let err = Dataset::open(&data)
        .unwrap()
        .with_camera(&Disk, Some("top"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no camera \"top\"") && err.contains("wrist"),
        "{err}"
    );

    let bin = env!("CARGO_BIN_EXE_dmbn");
    let data_s = data.to_str().unwrap();
    let out = dmbn(bin, &["inspect", data_s]);
    assert!(out.status.success(), "{}", text(&out));
    let report = text(&out);
    assert!(report.contains("8 joint values a step"), "{report}");
    assert!(report.contains("wrist_3"), "{report}");
    assert!(
        report.contains("4 sequences have no object_<id>.txt"),
        "{report}"
    );
}

#[test]
fn bad_joint_files_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("robot");
    robot_dataset(&data, 3, 6);
    let bin = env!("CARGO_BIN_EXE_dmbn");
    // One file of 7 values a step among files of 8: named, with both counts.
    let file = data.join("2/reach/joint_2.txt");
    let seven: String = std::fs::read_to_string(&file)
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once(' ').unwrap().0.to_string() + "\n")
        .collect();
    std::fs::write(&file, seven).unwrap();
    let out = dmbn(bin, &["inspect", data.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let err = text(&out);
    assert!(
        err.contains("joint_2.txt") && err.contains("7 joint values a step, expected 8"),
        "{err}"
    );
    // A row of another width inside one file: the file and its line.
    let file = data.join("1/reach/joint_1.txt");
    let mut rows = std::fs::read_to_string(&file).unwrap();
    rows += "1 2 3\n";
    std::fs::write(&file, rows).unwrap();
    let out = dmbn(bin, &["inspect", data.to_str().unwrap()]);
    let err = text(&out);
    assert!(
        err.contains("joint_1.txt line 7") && err.contains("expected 8 columns, found 3"),
        "{err}"
    );
    // An image of another size inside one sequence.
    let dir = data.join("0/reach");
    frame(32, 32, 0.5, 0).save(dir.join("3.png")).unwrap();
    let dataset = Dataset::open(&data).unwrap();
    let err = dataset
        .read(&dataset.sequences()[0], Some(64))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("3.png") && err.contains("expected a 48x32 frame") && err.contains("32x32"),
        "{err}"
    );
}

#[test]
fn train_predict_and_score_on_eight_joint_values() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("robot");
    robot_dataset(&data, 4, 12);
    let (data_s, out) = (data.to_str().unwrap(), tmp.path().join("run"));
    let train = dmbn(
        env!("CARGO_BIN_EXE_train"),
        &[
            "--data",
            data_s,
            "--out",
            out.to_str().unwrap(),
            "--model",
            "attn",
            "--steps",
            "4",
            "--batch",
            "2",
            "--val-fraction",
            "0.25",
            "--val-every",
            "2",
            "--camera",
            "wrist",
        ],
    );
    assert!(train.status.success(), "{}", text(&train));
    let model = out.join("model.dmbn");
    let header = read_header(&std::fs::read(&model).unwrap()).unwrap();
    assert_eq!(header.config.joint_count(), D);
    assert_eq!(header.config.joint_names.unwrap()[6], "wrist_3");
    assert_eq!(header.normalization.mean.len(), D);

    let bin = env!("CARGO_BIN_EXE_dmbn");
    let model_s = model.to_str().unwrap();
    let predicted = tmp.path().join("predicted");
    let out = dmbn(
        bin,
        &[
            "predict",
            "--model",
            model_s,
            "--data",
            data_s,
            "--sequence",
            "3/reach",
            "--camera",
            "wrist",
            "--observe",
            "0,5,11",
            "--out",
            predicted.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", text(&out));
    assert!(predicted.join("joints.png").is_file());
    let out = dmbn(
        bin,
        &[
            "score", "--model", model_s, "--data", data_s, "--ids", "3-3", "--camera", "wrist",
        ],
    );
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("joint"), "{}", text(&out));

    // The shipped 7-value model is refused on 8-value data, saying both counts.
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/attn-sim.dmbn");
    let out = dmbn(
        bin,
        &[
            "score",
            "--model",
            shipped.to_str().unwrap(),
            "--data",
            data_s,
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let err = text(&out);
    assert!(
        err.contains("reads 7 joint values a step") && err.contains("has 8"),
        "{err}"
    );
    // Imitation performs the simulator's arm: refused for this data, saying why.
    let out = dmbn(
        bin,
        &[
            "imitate", "--model", model_s, "--data", data_s, "--ids", "3-3",
        ],
    );
    assert!(!out.status.success());
    let err = text(&out);
    assert!(err.contains("simulator"), "{err}");
}
