//! The dataset converters (python/dmbn_convert: LeRobot v2.x/v3.0 and robomimic HDF5 into the
//! DMBN layout, and the DMBN layout back to LeRobot v2.1): their pytest suite, run with a
//! Python that has pyarrow, av, h5py and pytest (`.ci/setup` makes one); skipped without.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

/// `$DMBN_PYTHON_CONVERT`, the converters' venv (`~/.cache/dmbn/venv-convert`), or
/// `python3`: the first that imports the converters' dependencies.
fn python_with_converter_deps() -> Option<PathBuf> {
    let venv = std::env::var_os("HOME")
        .map(|h| PathBuf::from(h).join(".cache/dmbn/venv-convert/bin/python"));
    let candidates = std::env::var_os("DMBN_PYTHON_CONVERT")
        .map(PathBuf::from)
        .into_iter()
        .chain(venv)
        .chain([PathBuf::from("python3")]);
    for python in candidates {
        let ok = Command::new(&python)
            .args(["-c", "import pyarrow, av, h5py, pytest"])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Some(python);
        }
    }
    None
}

#[test]
fn converters_pass_their_pytest_suite() {
    let Some(python) = python_with_converter_deps() else {
        support::skip(
            "no Python with pyarrow, av, h5py and pytest (set DMBN_PYTHON_CONVERT, or run \
             pip install -r python/requirements-convert.txt)",
        );
        return;
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let output = Command::new(&python)
        .args([
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "python/tests/test_convert.py",
        ])
        .current_dir(root)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("runs pytest");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stdout}");
    assert!(
        output.status.success(),
        "{} -m pytest python/tests/test_convert.py failed ({}):\n{stdout}\n{stderr}",
        python.display(),
        output.status
    );
}

/// A LeRobot v2.1 dataset and a robomimic file, written by the suite's fixtures (the formats'
/// own libraries) and converted by python/tests/converted.py, then trained on and scored by
/// the usual commands: other robots' data (8 and 9 joint values a step, 48 × 32 frames, no
/// object files) from end to end. (The page opens the same folders: folder.test.mjs.)
#[test]
fn converted_datasets_train_and_score() {
    let Some(python) = python_with_converter_deps() else {
        support::skip("no Python with pyarrow, av, h5py and pytest (see the test above)");
        return;
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let made = Command::new(&python)
        .args(["python/tests/converted.py", t.to_str().unwrap()])
        .current_dir(root)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    for (name, joints) in [("from-lerobot", 8), ("from-robomimic", 9)] {
        let data = t.join(name);
        let run = t.join(format!("run-{name}"));
        let said = |o: &std::process::Output| {
            format!(
                "{name}: {}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            )
        };
        let train = Command::new(env!("CARGO_BIN_EXE_train"))
            .args([
                "--data",
                data.to_str().unwrap(),
                "--out",
                run.to_str().unwrap(),
            ])
            .args(support::TRAIN_TWO_STEPS)
            .output()
            .unwrap();
        assert!(train.status.success(), "{}", said(&train));
        let model = run.join("model.dmbn");
        let header = dmbn::model::read_header(&std::fs::read(&model).unwrap()).unwrap();
        assert_eq!(header.config.joint_count(), joints, "{name}");
        assert!(
            header.config.joint_names.is_some(),
            "{name}: names from dataset.json"
        );
        let score = Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .args(["score", "--model", model.to_str().unwrap()])
            .args([
                "--data",
                data.to_str().unwrap(),
                "--ids",
                "2-2",
                "--observations",
                "3",
            ])
            .output()
            .unwrap();
        assert!(score.status.success(), "{}", said(&score));
    }
}
