//! The diagnostics of `experiments/` and the examples of `examples/` run on tiny simulated
//! inputs, so that they cannot rot: each is compiled here as a module and its logic called as
//! its `main` calls it (`cargo run --release --example NAME` runs them at full size).
#![cfg(not(target_arch = "wasm32"))]

mod support;

#[allow(dead_code)]
#[path = "../experiments/push_reach.rs"]
mod push_reach;

#[allow(dead_code)]
#[path = "../experiments/push_oracle.rs"]
mod push_oracle;

#[allow(dead_code)]
#[path = "../examples/strip.rs"]
mod strip;

use dmbn::data::Dataset;
use dmbn::predict::Predictor;
use dmbn::sim::Action;

/// `push_reach` on two unseen pushes: the page's default model imitates both, every bin of
/// steps before the push's end has an error, and each miss says how far short it stopped.
#[test]
fn push_reach_bins_the_joint_error_around_the_push_s_end() {
    let tmp = tempfile::tempdir().unwrap();
    support::simulated_dataset(tmp.path(), 0..2, &[Action::Move], 2_100_000);
    let predictor = Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap();
    let dataset = Dataset::open(tmp.path()).unwrap();
    let reach = push_reach::push_reach(&predictor, &dataset, 5).unwrap();
    assert_eq!(reach.pushes, 2);
    assert_eq!(
        reach.rmse.len(),
        ((push_reach::TO - push_reach::FROM) / push_reach::BIN) as usize
    );
    // Every push ends after its first 40 steps (the bins before its end are all filled);
    // the last bins may be empty: a push can end fewer than 20 steps before the action does.
    let before = (-push_reach::FROM / push_reach::BIN) as usize;
    assert!(
        reach.rmse[..before].iter().all(|r| r.is_finite())
            && reach
                .rmse
                .iter()
                .all(|r| r.is_nan() || (0.0..0.5).contains(r)),
        "{:?}",
        reach.rmse
    );
    for &(id, short, phase) in &reach.missed {
        assert!(id < 2 && short.is_finite() && (0.0..=1.0).contains(&phase));
    }
    let table = reach.table();
    assert!(table.contains("| -40 to -36 |"), "{table}");
    assert!(table.contains("of 2 pushes missed"), "{table}");
}

/// `push_oracle` on one push (the first of docs/results.md's set, at its σ of 1 cm): its
/// posterior-mean joints over the timings the glimpses leave open land it, within 0.02 rad of
/// the demonstration's (docs/results.md: 100 of 100, 0.008 rad; here 0.006 rad, 25,782 of the
/// 39,375 timings weighing, about 8 s in the tests' build).
#[test]
fn push_oracle_lands_a_push_from_its_posterior_mean_joints() {
    let push = push_oracle::oracle_push(300_000, 0.01, 5).unwrap();
    println!("{push:?}");
    assert!(push.landed, "{push:?}");
    assert_eq!(push.miss, None);
    assert!(
        0 < push.weighing && push.weighing < push.timings,
        "{push:?}"
    );
    let rmse = (push.se / push.values as f64).sqrt();
    assert!(rmse < 0.02, "{rmse}");
}

/// `strip`: two rows (grasp, move) of 8 frames, and a line per action.
#[test]
fn strip_renders_a_row_of_frames_per_action() {
    let (image, lines) = strip::strip(3, 64).unwrap();
    assert_eq!(image.dimensions(), (8 * 64, 2 * 64));
    assert_eq!(lines.len(), 2);
    assert!(lines[0].starts_with("grasp: ") && lines[1].starts_with("move: "));
    // Not a blank canvas: the scene is drawn in both rows.
    for row in 0..2 {
        let pixels = (0..8 * 64).map(|x| image.get_pixel(x, row * 64 + 32).0);
        assert!(pixels.filter(|p| p != &[0, 0, 0]).count() > 100);
    }
}
