//! The imitation benchmark: the arm performs joint trajectories (recorded, predicted, wrong),
//! the outcomes are judged, `dmbn imitate` reports them, and the golden imitation the wasm
//! tests must agree with. Native only (the wasm tests are in tests/web.rs).
#![cfg(not(target_arch = "wasm32"))]

mod golden;
#[path = "golden/imitation.rs"]
mod golden_imitation;
mod support;

use std::path::Path;
use std::process::Command;

use dmbn::data::Sequence;
use dmbn::imitate::{enact, imitate, mean_motion, replay, with_noise, OutcomeSums, Task};
use dmbn::predict::Predictor;
use dmbn::quality::MeanMotion;
use dmbn::sim::{episode, perform, Action, Outcome, PushMiss, SimError, Simulator, Trajectory};

fn object(demo: &Sequence) -> [f32; 2] {
    let object = demo.object.as_ref().unwrap();
    [object[0][0], object[0][1]]
}

#[test]
fn replaying_the_recorded_joints_reproduces_the_outcome() {
    for action in Action::ALL {
        for seed in 400..406 {
            let demo = episode(action, seed, 64).unwrap();
            let r = replay(&demo, action).unwrap();
            let o = r.outcome;
            assert!(o.success, "{action} seed {seed}: {o:?}");
            assert!(o.path_error_cm < 1.0, "{action} seed {seed}: {o:?}");
            assert!(o.object_error_cm < 2.0, "{action} seed {seed}: {o:?}");
            assert_eq!(r.performance.len(), demo.len());
            assert_eq!(r.joint_rmse(), 0.0);
        }
    }
}

#[test]
fn performing_is_deterministic_and_starts_at_the_first_row() {
    let demo = episode(Action::Grasp, 3, 64).unwrap();
    let t = Trajectory::new(support::fixed_rows(&demo.joints)).unwrap();
    let a = perform(&t, object(&demo), 64).unwrap();
    let [x, y] = object(&demo);
    let b = Simulator::performing(&t, x, y, 64).unwrap().run();
    assert_eq!(a.digest(), b.digest());
    assert_eq!(a.joints[0][..6], demo.joints[0][..6]);
    assert_eq!(a.frame(0), demo.frame(0), "same start, same scene");
}

#[test]
fn wrong_trajectories_fail_their_outcome() {
    // A grasp whose gripper never closes, and a push that never leaves home.
    let demo = episode(Action::Grasp, 5, 64).unwrap();
    let open: Vec<[f32; 7]> = support::fixed_rows(&demo.joints)
        .iter()
        .map(|r| {
            let mut r = *r;
            r[6] = 0.0;
            r
        })
        .collect();
    let p = perform(&Trajectory::new(open).unwrap(), object(&demo), 64).unwrap();
    let o = Outcome::judge(Action::Grasp, &p, &demo).unwrap();
    assert!(!o.success && o.lift_cm < 2.0, "{o:?}");
    assert!(o.summary().starts_with("missed"), "{}", o.summary());
    assert_eq!(o.push_error_cm, None, "a grasp has no push direction");

    let demo = episode(Action::Move, 5, 64).unwrap();
    let home = vec![support::fixed_rows(&demo.joints)[0]; demo.len()];
    let p = perform(&Trajectory::new(home).unwrap(), object(&demo), 64).unwrap();
    let o = Outcome::judge(Action::Move, &p, &demo).unwrap();
    assert!(!o.success && o.object_error_cm > 5.0, "{o:?}");
    assert!(o.path_error_cm > 5.0, "{o:?}");
    // Never pushed: short by the demonstration's whole travel, not aside.
    let e = o.push_error_cm.expect("a push has a direction");
    assert_eq!(e.miss(), PushMiss::Short, "{e:?}");
    assert!(
        (e.along.abs() - o.object_error_cm).abs() < 0.5,
        "{e:?} {o:?}"
    );
    assert!(o.summary().contains("cm short"), "{}", o.summary());
}

#[test]
fn bad_trajectories_and_placements_are_errors() {
    let demo = episode(Action::Move, 2, 64).unwrap();
    let mut rows = support::fixed_rows(&demo.joints);
    rows[3][1] = f32::NAN;
    let err = Trajectory::new(rows).unwrap_err().to_string();
    assert!(err.contains("row 3, column 1 is NaN"), "{err}");
    let err = Trajectory::from_flat(&[0.0; 20]).unwrap_err().to_string();
    assert!(err.contains("20 values"), "{err}");
    let t = Trajectory::new(support::fixed_rows(&demo.joints)).unwrap();
    assert!(matches!(
        perform(&t, [2.0, 0.5], 64),
        Err(SimError::ObjectOutOfRegion { .. })
    ));
    assert!(matches!(
        perform(&t, object(&demo), 65),
        Err(SimError::ImageSize(65))
    ));
}

#[test]
fn frames_only_imitation_never_reads_the_observed_joints() {
    let predictor = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let demo = episode(Action::Grasp, 21, 64).unwrap();
    let a = imitate(&predictor, &demo, Action::Grasp, Task::Frames, 5, 1.0)
        .unwrap()
        .unwrap();
    let mut blind = demo.clone();
    blind.joints = (0..blind.len())
        .map(|_| [1.0, -1.0, 0.5, 0.0, 2.0, -2.0, -0.1])
        .collect();
    let b = imitate(&predictor, &blind, Action::Grasp, Task::Frames, 5, 1.0)
        .unwrap()
        .unwrap();
    assert_eq!(a.trajectory, b.trajectory);
    assert_eq!(
        a.observed,
        Task::Frames.steps(demo.len(), 5).unwrap().observed
    );
    assert_eq!(a.predicted_from, 0);
    assert!(a.joint_rmse() > 0.0);
}

#[test]
fn finish_performs_the_observed_part_as_recorded() {
    let predictor = Predictor::load(support::asset("models/dmbn-sim.dmbn")).unwrap();
    let demo = episode(Action::Move, 8, 64).unwrap();
    let f = imitate(&predictor, &demo, Action::Move, Task::Finish, 5, 0.5)
        .unwrap()
        .unwrap();
    let from = f.predicted_from;
    let recorded = support::fixed_rows(&demo.joints);
    assert_eq!(from, f.observed.last().unwrap() + 1);
    assert_eq!(f.trajectory[..from], recorded[..from]);
    assert_ne!(f.trajectory[from..], recorded[from..]);
    assert_eq!(f.joint_steps, demo.len() - from);
    // The floor: the mean motion of a set of pushes after the same recorded part.
    let set: Vec<Sequence> = (30..36)
        .map(|s| episode(Action::Move, s, 64).unwrap())
        .collect();
    let mean = MeanMotion::fit(set.iter().map(|s| ("move", s))).unwrap();
    let floor = mean_motion(&demo, Action::Move, Task::Finish, 5, &mean)
        .unwrap()
        .unwrap();
    assert_eq!(floor.trajectory[..from], recorded[..from]);
    assert!(floor.observed.is_empty());
    let grasps = MeanMotion::fit(set.iter().map(|s| ("grasp", s))).unwrap();
    let err = mean_motion(&demo, Action::Move, Task::Finish, 5, &grasps).unwrap_err();
    assert!(err.to_string().contains("no move sequence"), "{err}");
}

#[test]
fn noisy_replays_err_by_the_rmse_asked_for() {
    let demo = episode(Action::Move, 6, 64).unwrap();
    // No noise: the ceiling itself.
    let exact = with_noise(&demo, Action::Move, Task::Frames, 5, 0.0, 1)
        .unwrap()
        .unwrap();
    let ceiling = replay(&demo, Action::Move).unwrap();
    assert_eq!(exact.performance.digest(), ceiling.performance.digest());
    let recorded = support::fixed_rows(&demo.joints);
    for task in Task::ALL {
        let n = with_noise(&demo, Action::Move, task, 5, 0.02, 1)
            .unwrap()
            .unwrap();
        let from = n.predicted_from;
        assert_eq!(n.trajectory[..from], recorded[..from], "{task}");
        assert!(
            (n.joint_rmse() - 0.02).abs() < 1e-4,
            "{task}: {}",
            n.joint_rmse()
        );
        assert!(n.observed.is_empty());
        // The gripper column is the recording's.
        assert!(n
            .trajectory
            .iter()
            .zip(&demo.joints)
            .all(|(a, b)| a[6] == b[6]));
    }
}

#[test]
fn rows_count_successes_against_the_ceiling() {
    let demo = episode(Action::Grasp, 9, 64).unwrap();
    let good = replay(&demo, Action::Grasp).unwrap();
    let mut bad = good.clone();
    bad.outcome.success = false;
    let (mut ceiling, mut model) = (OutcomeSums::default(), OutcomeSums::default());
    for _ in 0..4 {
        ceiling.add(&good);
    }
    model.add(&good);
    model.add(&good);
    model.add(&good);
    model.add(&bad);
    let row = model.row("m", "grasp", Some(&ceiling));
    assert_eq!((row.episodes, row.successes), (4, 3));
    assert!((row.of_ceiling.unwrap() - 0.75).abs() < 1e-12);
    assert_eq!(row.push_misses, None, "grasps have no push misses");
    assert_eq!(ceiling.row("c", "grasp", None).of_ceiling, None);
}

#[test]
fn rows_say_how_pushes_missed_and_which_joint_erred() {
    let demo = episode(Action::Move, 5, 64).unwrap();
    let good = replay(&demo, Action::Move).unwrap();
    // The base joint 0.08 rad off at every step, the other joints as recorded: the finger
    // meets the object off its centre and knocks it aside (measured: 9.9 cm to the right).
    let mut rows = support::fixed_rows(&demo.joints);
    rows.iter_mut().for_each(|r| r[0] -= 0.08);
    let turned = enact(&demo, Action::Move, rows, Vec::new()).unwrap();
    let e = turned.outcome.push_error_cm.unwrap();
    assert_eq!(e.miss(), PushMiss::Aside, "{e:?}");
    assert!(turned.outcome.summary().contains("to the right"), "{e:?}");
    // Never leaving home: short.
    let home = enact(
        &demo,
        Action::Move,
        vec![support::fixed_rows(&demo.joints)[0]; demo.len()],
        vec![],
    )
    .unwrap();
    let mut sums = OutcomeSums::default();
    for i in [&good, &turned, &home, &home] {
        sums.add(i);
    }
    let row = sums.row("m", "move", None);
    let misses = row.push_misses.expect("a push row counts its misses");
    assert_eq!((misses.short, misses.long, misses.aside), (2, 0, 1));
    // Per joint: the turned trajectory errs 0.08 rad in the base joint alone.
    assert!((turned.joint_se[0] - 0.0064 * demo.len() as f64).abs() < 1e-4);
    assert_eq!(turned.joint_se[1..], [0.0; 5]);
    let steps = 4.0 * demo.len() as f64;
    let se = |j: usize| {
        [&turned, &home, &home]
            .iter()
            .map(|i| i.joint_se[j])
            .sum::<f64>()
    };
    assert_eq!(row.joint_rmse_per_joint.len(), 6);
    for j in 0..6 {
        assert!((row.joint_rmse_per_joint[j] - (se(j) / steps).sqrt()).abs() < 1e-9);
    }
    let total: f64 = (0..6).map(se).sum();
    assert!((row.joint_rmse - (total / (steps * 6.0)).sqrt()).abs() < 1e-9);
}

/// The golden imitation: native writes it (`DMBN_BLESS=1`) and must reproduce it; the wasm
/// tests must agree with it.
#[test]
fn default_model_reproduces_the_golden_imitation() {
    let predictor = Predictor::from_bytes(golden_imitation::MODEL).unwrap();
    let demo = episode(golden_imitation::ACTION, golden_imitation::SEED, 64).unwrap();
    let got: Vec<golden_imitation::Sample> = Task::ALL
        .iter()
        .map(|&task| {
            let i = imitate(
                &predictor,
                &demo,
                golden_imitation::ACTION,
                task,
                5,
                task.default_blend(),
            )
            .unwrap()
            .unwrap();
            golden_imitation::Sample::of(&i.trajectory, &i.outcome, &i.performance.digest())
        })
        .collect();
    let replayed = replay(&demo, golden_imitation::ACTION).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/imitation.json");
    if std::env::var_os("DMBN_BLESS").is_some() {
        assert!(
            std::env::var_os("CI").is_none(),
            "DMBN_BLESS is refused under CI"
        );
        let golden = golden_imitation::Golden {
            tasks: got,
            replay_digest: replayed.performance.digest(),
        };
        std::fs::write(&path, serde_json::to_string(&golden).unwrap() + "\n").unwrap();
        return;
    }
    let want = golden_imitation::expected();
    assert_eq!(replayed.performance.digest(), want.replay_digest);
    for (got, want) in got.iter().zip(&want.tasks) {
        golden_imitation::assert_agrees(got, want, 0.0);
    }
}

#[test]
fn dmbn_imitate_prints_tables_and_writes_json() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..3, &Action::ALL, 500_000);
    let json = tmp.path().join("imitate.json");
    let out = Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(["imitate", "--model"])
        .arg(support::asset("models/dmbn-sim.dmbn"))
        .arg("--data")
        .arg(&data)
        .args(["--ids", "0-2", "--noise", "0.002", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("task frames (5 observations, blend 1)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("task finish (3 observations, blend 0.5)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| grasp | ceiling: recorded joints | 3 | 3/3 (100%)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| move | floor: mean motion | 3 |"),
        "{stdout}"
    );
    let reports: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(reports.as_array().unwrap().len(), 2);
    assert_eq!(reports[0]["task"], "frames");
    // Per action: ceiling, floor, the noisy replay, the model.
    assert_eq!(reports[0]["rows"].as_array().unwrap().len(), 8);
    assert_eq!(
        reports[0]["rows"][2]["name"],
        "recorded joints + 0.002 rad noise"
    );
    let noisy = reports[0]["rows"][2]["joint_rmse"].as_f64().unwrap();
    assert!((noisy - 0.002).abs() < 1e-4, "{noisy}");
    assert_eq!(reports[0]["rows"][3]["name"], "dmbn-sim.dmbn");
    // Every performance: 3 ids × 2 actions × 4 rows.
    assert_eq!(reports[1]["performances"].as_array().unwrap().len(), 24);
    assert!(reports[1]["performances"][0]["success"].is_boolean());
    // Pushes say how they missed; every row says which joint erred.
    assert!(stdout.contains("misses: short / long / aside"), "{stdout}");
    let rows = reports[0]["rows"].as_array().unwrap();
    for row in rows {
        assert_eq!(row["joint_rmse_per_joint"].as_array().unwrap().len(), 6);
        let misses = &row["push_misses"];
        if row["action"] == "grasp" {
            assert!(misses.is_null(), "{row}");
            continue;
        }
        let n = |k: &str| misses[k].as_u64().unwrap();
        let missed = row["episodes"].as_u64().unwrap() - row["successes"].as_u64().unwrap();
        assert_eq!(n("short") + n("long") + n("aside"), missed, "{row}");
    }
    let floor = &rows[5];
    assert_eq!(floor["name"], "floor: mean motion");
    assert!(
        floor["joint_rmse_per_joint"][0].as_f64().unwrap() > 0.0,
        "{floor}"
    );

    // Refused settings: the command fails and says why (stderr).
    let refused = |extra: &[&str]| {
        let err = Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .args(["imitate", "--model"])
            .arg(support::asset("models/dmbn-sim.dmbn"))
            .arg("--data")
            .arg(&data)
            .args(extra)
            .output()
            .unwrap();
        assert!(!err.status.success(), "{extra:?} was accepted");
        String::from_utf8_lossy(&err.stderr).into_owned()
    };
    // finish observes its first 30% at 3 steps: --observations with it is refused, not ignored.
    let said = refused(&["--task", "finish", "--observations", "7"]);
    assert!(
        said.contains("--observations 7: the finish task observes"),
        "{said}"
    );
    // A noise that is no RMSE.
    let stderr = refused(&["--noise", "2"]);
    assert!(
        stderr.contains("expected a joint RMSE in radians"),
        "{stderr}"
    );
    // No sequence in the ids asked for.
    assert!(refused(&["--ids", "7-9"]).contains("no sequence with an id in"));
}

#[test]
fn dmbn_imitate_names_an_object_it_cannot_place() {
    // An object off the simulator's table (the original DMBN data's frame, say).
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let mut demo = episode(Action::Grasp, 1, 64).unwrap();
    for o in demo.object.as_mut().unwrap() {
        o[0] = 1.5;
    }
    let mut writer = dmbn::data::DatasetWriter::create(&data).unwrap();
    writer.write(0, "grasp", &demo).unwrap();
    writer.finish().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(["imitate", "--model"])
        .arg(support::asset("models/dmbn-sim.dmbn"))
        .arg("--data")
        .arg(&data)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("outside the placement region"), "{stderr}");
}
