//! The second arm: the Panda-like 7-joint arm records 8 joint values a step, is deterministic,
//! lifts the object when its own grasps are replayed and lands its own pushes, and
//! `dmbn simulate --arm panda` writes its data; rows of a width no arm has are refused.
use std::process::Command;

mod golden;
mod support;

use dmbn::data::{read_joints, Disk};
use dmbn::sim::{
    episode, episode_with_arm, perform, Action, Arm, Outcome, SimError, Simulator, Trajectory,
    OBJECT_HALF_HEIGHT,
};

/// Seeds whose replays are checked (a handful: each is a scripted episode and its replay).
const SEEDS: [u64; 4] = [0, 1, 2, 3];

fn object(seq: &dmbn::data::Sequence) -> [f32; 2] {
    let o = seq.object.as_ref().unwrap()[0];
    [o[0], o[1]]
}

#[test]
fn panda_episodes_have_eight_values_a_step_and_are_deterministic() {
    for action in Action::ALL {
        let a = episode_with_arm(Arm::Panda, action, 11, 64).unwrap();
        let b = episode_with_arm(Arm::Panda, action, 11, 64).unwrap();
        assert_eq!(a.joints.width(), 8);
        assert_eq!(
            a.digest(),
            b.digest(),
            "{action}: the same seed, the same episode"
        );
        // The same script as the UR5's: same placement, same number of steps.
        let ur5 = episode(action, 11, 64).unwrap();
        assert_eq!(a.len(), ur5.len());
        assert_eq!(object(&a), object(&ur5));
        assert_ne!(a.frames, ur5.frames, "{action}: another arm is drawn");
        let c = episode_with_arm(Arm::Panda, action, 12, 64).unwrap();
        assert_ne!(a.digest(), c.digest());
        let [x, y] = object(&a);
        let d = Simulator::with_object_on(Arm::Panda, action, x, y, 11, 64)
            .unwrap()
            .run();
        assert_eq!(a.digest(), d.digest());
        assert_eq!(a.joints[0][7], 0.0, "the gripper starts open");
    }
}

#[test]
fn panda_episode_and_its_replay_match_the_golden_digests() {
    // The wasm tests (tests/web.rs) check the same digests: native = wasm, bit for bit.
    let demo = episode_with_arm(Arm::Panda, Action::Move, 7, 64).unwrap();
    assert_eq!(demo.digest(), golden::GOLDEN_PANDA_MOVE_SEED7_64);
    let t = Trajectory::of_joints(demo.joints.clone()).unwrap();
    let replay = perform(&t, object(&demo), 64).unwrap();
    assert_eq!(replay.digest(), golden::GOLDEN_PANDA_MOVE_SEED7_REPLAY);
}

#[test]
fn panda_grasps_lift_and_pushes_move_and_their_replays_succeed() {
    for seed in SEEDS {
        for action in Action::ALL {
            let demo = episode_with_arm(Arm::Panda, action, seed, 64).unwrap();
            let o = demo.object.as_ref().unwrap();
            let (first, last) = (o[0], *o.last().unwrap());
            assert!((first[2] - OBJECT_HALF_HEIGHT).abs() < 1e-3);
            match action {
                Action::Grasp => assert!(last[2] > 0.15, "seed {seed}: lifted to {}", last[2]),
                Action::Move => {
                    let moved =
                        ((last[0] - first[0]).powi(2) + (last[1] - first[1]).powi(2)).sqrt();
                    assert!(moved > 0.05, "seed {seed}: pushed {moved} m");
                    assert!((last[2] - OBJECT_HALF_HEIGHT).abs() < 0.01, "upright");
                }
            }
            let t = Trajectory::of_joints(demo.joints.clone()).unwrap();
            assert_eq!(t.arm(), Arm::Panda);
            let replay = perform(&t, object(&demo), 64).unwrap();
            assert_eq!(replay.joints.width(), 8);
            let outcome = Outcome::judge(action, &replay, &demo).unwrap();
            assert!(
                outcome.success,
                "{action} seed {seed}: {}",
                outcome.summary()
            );
        }
    }
}

#[test]
fn rows_of_nine_values_are_refused_naming_the_widths() {
    let rows = vec![[0.0f32; 9]; 4];
    let err = Trajectory::new(rows).unwrap_err();
    assert!(matches!(err, SimError::ArmWidth(9)), "{err}");
    let text = err.to_string();
    assert!(text.contains("7 (ur5) or 8 (panda)"), "{text}");
    let err = "kuka".parse::<Arm>().unwrap_err().to_string();
    assert!(err.contains("\"ur5\" or \"panda\""), "{err}");
    // Eight-value rows: the Panda holding still at its first step.
    let demo = episode_with_arm(Arm::Panda, Action::Grasp, 4, 64).unwrap();
    let still = vec![<[f32; 8]>::try_from(demo.joints.row(0)).unwrap(); 10];
    let p = perform(&Trajectory::new(still).unwrap(), object(&demo), 64).unwrap();
    assert_eq!((p.len(), p.joints.width()), (10, 8));
    let z = p.object.as_ref().unwrap()[9][2];
    assert!(
        (z - OBJECT_HALF_HEIGHT).abs() < 1e-3,
        "the object stays put"
    );
}

#[test]
fn simulate_arm_panda_writes_eight_column_joint_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("panda");
    let run = Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args([
            "simulate",
            "--arm",
            "panda",
            "--sequences",
            "1",
            "--seed",
            "3",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stdout).contains("panda arm"));
    for action in Action::ALL {
        let dir = out.join("0").join(action.name());
        let joints = read_joints(&Disk, &dir, 0).unwrap();
        assert_eq!(joints.width(), 8, "{action}");
        let expected = episode_with_arm(Arm::Panda, action, 3, 64).unwrap();
        assert_eq!(joints.len(), expected.len());
    }
    let bad = Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args([
            "simulate",
            "--arm",
            "kuka",
            "--sequences",
            "1",
            "--seed",
            "3",
        ])
        .arg("--out")
        .arg(tmp.path().join("kuka"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("\"ur5\" or \"panda\""));
}

#[test]
fn the_panda_s_data_goes_through_train_score_and_imitate() {
    let tmp = tempfile::tempdir().unwrap();
    let (data, run) = (tmp.path().join("panda"), tmp.path().join("run"));
    let exe = |bin: &str, args: &[&str]| {
        let path = match bin {
            "train" => env!("CARGO_BIN_EXE_train"),
            _ => env!("CARGO_BIN_EXE_dmbn"),
        };
        let o = Command::new(path).args(args).output().unwrap();
        let said = format!(
            "{bin} {args:?}: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.status.success(), "{said}");
        said
    };
    let (d, r) = (data.to_str().unwrap(), run.to_str().unwrap());
    exe(
        "dmbn",
        &[
            "simulate",
            "--arm",
            "panda",
            "--sequences",
            "3",
            "--seed",
            "5",
            "--out",
            d,
        ],
    );
    let train: Vec<&str> = ["--data", d, "--out", r]
        .into_iter()
        .chain(support::TRAIN_TWO_STEPS)
        .collect();
    exe("train", &train);
    let model = run.join("model.dmbn");
    let header = dmbn::model::read_header(&std::fs::read(&model).unwrap()).unwrap();
    assert_eq!(header.config.joint_count(), 8);
    let m = model.to_str().unwrap();
    let score = exe(
        "dmbn",
        &[
            "score",
            "--model",
            m,
            "--data",
            d,
            "--ids",
            "2-2",
            "--samples",
            "2",
        ],
    );
    assert!(score.contains("energy score"), "{score}");
    let imitate = exe(
        "dmbn",
        &[
            "imitate", "--model", m, "--data", d, "--ids", "2-2", "--task", "frames",
        ],
    );
    assert!(imitate.contains("ceiling: recorded joints"), "{imitate}");
}
