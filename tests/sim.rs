//! The simulator: determinism (golden hash shared with the wasm tests), episode lengths,
//! physics outcomes of both actions, frame content and bad settings.
mod golden;

use dmbn::sim::{episode, Action, SimError, Simulator, OBJECT_HALF_HEIGHT};

#[test]
fn golden_digest() {
    let seq = episode(Action::Grasp, 7, 64).unwrap();
    assert_eq!(seq.digest(), golden::GOLDEN_GRASP_SEED7_64);
}

#[test]
fn same_seed_same_episode_and_placement_is_reproducible() {
    for action in Action::ALL {
        let a = episode(action, 11, 64).unwrap();
        let b = episode(action, 11, 64).unwrap();
        assert_eq!(a, b);
        let [x, y, _] = a.object.as_ref().unwrap()[0];
        let c = Simulator::with_object(action, x, y, 11, 64).unwrap().run();
        assert_eq!(
            a.digest(),
            c.digest(),
            "with_object at new()'s placement must match"
        );
        let d = episode(action, 12, 64).unwrap();
        assert_ne!(a.digest(), d.digest(), "another seed gives another episode");
    }
}

#[test]
fn lengths_in_the_originals_range() {
    for seed in 0..24 {
        let g = Simulator::new(Action::Grasp, seed, 64).unwrap().len();
        let m = Simulator::new(Action::Move, seed, 64).unwrap().len();
        assert!((34..=86).contains(&g), "grasp seed {seed}: {g} steps");
        assert!((53..=114).contains(&m), "move seed {seed}: {m} steps");
    }
}

#[test]
fn grasp_lifts_the_object_and_move_pushes_it() {
    for seed in 0..6 {
        let g = episode(Action::Grasp, seed, 64).unwrap();
        let object = g.object.as_ref().unwrap();
        let (first, last) = (object[0], *object.last().unwrap());
        assert!(
            last[2] > 0.15,
            "grasp seed {seed}: object ends at z = {}",
            last[2]
        );
        assert_eq!(g.joints[0][6], 0.0, "gripper starts open");
        assert!(g.joints[g.len() - 1][6] < -0.005, "gripper ends closed");
        // The object rises with the grasp point (held, not teleported).
        let tcp = g.endpoint.as_ref().unwrap().last().unwrap();
        assert!(
            (tcp[2] - last[2]).abs() < 0.03,
            "object follows the fingers"
        );
        assert!((first[2] - OBJECT_HALF_HEIGHT).abs() < 1e-3);

        let m = episode(Action::Move, seed, 64).unwrap();
        let object = m.object.as_ref().unwrap();
        let (first, last) = (object[0], *object.last().unwrap());
        let moved = ((last[0] - first[0]).powi(2) + (last[1] - first[1]).powi(2)).sqrt();
        assert!(moved > 0.05, "move seed {seed}: object moved {moved} m");
        assert!(
            (last[2] - OBJECT_HALF_HEIGHT).abs() < 0.01,
            "object stays upright on the table"
        );
        assert!(
            m.joints.rows().all(|j| j[6].abs() < 0.02),
            "move keeps the gripper open"
        );
    }
}

#[test]
fn joints_and_endpoint_are_finite_and_in_range() {
    let seq = episode(Action::Move, 3, 64).unwrap();
    let endpoint = seq.endpoint.as_ref().unwrap();
    for row in seq.joints.rows().chain(endpoint.iter().map(|r| &r[..])) {
        assert!(row.iter().all(|v| v.is_finite()));
    }
    for row in &seq.joints {
        assert!(row[..6]
            .iter()
            .all(|a| a.abs() <= 2.0 * std::f32::consts::PI));
    }
}

#[test]
fn frames_show_the_scene() {
    for size in [64u32, 128] {
        let seq = episode(Action::Grasp, 2, size).unwrap();
        assert_eq!(seq.frames.len(), seq.len() * (size * size * 3) as usize);
        let px = |k: usize, x: u32, y: u32| {
            let f = seq.frame(k);
            let i = ((y * size + x) * 3) as usize;
            [f[i], f[i + 1], f[i + 2]]
        };
        assert_eq!(px(0, 0, 0), [0, 0, 0], "black background in the top corner");
        let centre_low = px(0, size / 2, size * 3 / 4);
        let all = |k: usize, pred: &dyn Fn([u8; 3]) -> bool| {
            (0..size * size).any(|i| pred(px(k, i % size, i / size)))
        };
        assert!(
            centre_low.iter().all(|&c| c > 10),
            "table or arm in the lower middle"
        );
        assert!(all(0, &|[r, _, b]| b > 150 && r < 150), "blue joint caps");
        assert!(
            all(0, &|[r, g, b]| r > 150 && g > 150 && b > 150),
            "light arm links"
        );
        assert!(
            all(0, &|[r, g, b]| r == g && g == b && (30..60).contains(&r)),
            "dark table"
        );
        let last = seq.len() - 1;
        assert!(
            all(last, &|[r, g, b]| r > 150 && g > 130 && b < 60),
            "yellow object"
        );
    }
}

#[test]
fn bad_settings_are_errors() {
    assert!(matches!(
        Simulator::new(Action::Grasp, 0, 100).err(),
        Some(SimError::ImageSize(100))
    ));
    let err = Simulator::with_object(Action::Move, 0.5, 0.5, 0, 64)
        .err()
        .unwrap();
    assert!(matches!(err, SimError::ObjectOutOfRegion { .. }));
    assert!(err.to_string().contains("outside the placement region"));
    assert!(Simulator::with_object(Action::Move, f32::NAN, 0.5, 0, 64).is_err());
    let err = "jump".parse::<Action>().unwrap_err();
    assert_eq!(
        err.to_string(),
        "unknown action \"jump\": expected \"grasp\" or \"move\""
    );
}

#[test]
fn stepping_matches_run() {
    let mut sim = Simulator::new(Action::Grasp, 5, 64).unwrap();
    let seq = Simulator::new(Action::Grasp, 5, 64).unwrap().run();
    let mut k = 0;
    loop {
        assert_eq!(sim.joints(), seq.joints[k]);
        assert_eq!(sim.frame(), seq.frame(k));
        k += 1;
        if !sim.step() {
            break;
        }
    }
    assert_eq!(k, seq.len());
    assert!(!sim.step(), "stepping past the end changes nothing");
    assert_eq!(sim.step_index(), seq.len() - 1);
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn generate_writes_a_dataset_that_reads_back() {
    use dmbn::data::Dataset;
    use dmbn::sim::generate;

    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("data");
    let mut calls = Vec::new();
    let written = generate(&out, 0..2, 5, &[Action::Grasp], 64, 2, |done, total| {
        calls.push((done, total))
    })
    .unwrap();
    assert_eq!(written, out);
    assert_eq!(calls, [(0, 2), (1, 2), (2, 2)]);
    let dataset = Dataset::open(&out).unwrap();
    assert_eq!(dataset.ids(), [0, 1]);
    assert_eq!(dataset.actions(), ["grasp"]);
    for (id, seq_ref) in dataset.sequences().iter().enumerate() {
        let seq = dataset.read(seq_ref, None).unwrap();
        let expected = episode(Action::Grasp, 5 + id as u64, 64).unwrap();
        assert_eq!(seq.len(), expected.len());
        assert_eq!(
            seq.frames, expected.frames,
            "sequence {id}: the frames are PNGs"
        );
    }
    // Nothing but the dataset is left beside it.
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);

    let err = generate(&out, 0..1, 5, &[Action::Move], 64, 1, |_, _| {}).unwrap_err();
    assert!(matches!(err, SimError::Data(_)), "{err}");
    let err = generate(
        &tmp.path().join("b"),
        0..1,
        5,
        &[Action::Move],
        32,
        1,
        |_, _| {},
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "sequence 0 (move, seed 5): image size 32 is not supported: expected 64 or 128"
    );
    // The failed run left neither `b` nor its temporary folder.
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}
