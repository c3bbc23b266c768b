//! The wasm bindings under node (`wasm-pack test --node`): same episodes as native, usable
//! frames, and bad arguments as JS exceptions rather than traps. Compiles to nothing natively.
#![cfg(target_arch = "wasm32")]

mod golden;

use dmbn::web::{placement_region, run_episode, Episode, Simulator};
use wasm_bindgen::{JsError, JsValue};
use wasm_bindgen_test::wasm_bindgen_test;

/// The message of a JS exception, to check it says what was wrong.
fn message(err: JsError) -> String {
    js_sys::Error::from(JsValue::from(err)).message().into()
}

fn grasp7() -> Episode {
    run_episode("grasp".into(), 7.0, 64).expect("valid arguments")
}

#[wasm_bindgen_test]
fn digest_matches_native_golden() {
    assert_eq!(grasp7().digest(), golden::GOLDEN_GRASP_SEED7_64);
}

#[wasm_bindgen_test]
fn two_runs_are_identical() {
    let (a, b) = (grasp7(), grasp7());
    assert_eq!(a.digest(), b.digest());
    assert_eq!(a.joints(), b.joints());
    assert_eq!(a.frames(), b.frames());
}

#[wasm_bindgen_test]
fn arrays_have_episode_shapes() {
    let ep = grasp7();
    let t = ep.steps();
    assert!(t > 1);
    assert_eq!(ep.image_size(), 64);
    assert_eq!(ep.joints().len(), t * 7);
    assert_eq!(ep.endpoint().len(), t * 7);
    assert_eq!(ep.object().len(), t * 3);
    assert_eq!(ep.times().len(), t);
    assert_eq!(ep.frames().len(), t * 64 * 64 * 3);
    assert!(ep
        .joints()
        .iter()
        .chain(&ep.endpoint())
        .chain(&ep.object())
        .all(|v| v.is_finite()));
    assert_eq!(
        ep.frame(t - 1).unwrap(),
        ep.frames()[(t - 1) * 64 * 64 * 3..]
    );
}

#[wasm_bindgen_test]
fn frame_shows_table_and_yellow_object() {
    let ep = grasp7();
    let frame = ep.frame(0).unwrap();
    let pixels: Vec<&[u8]> = frame.chunks(3).collect();
    let dark = pixels.iter().any(|p| p.iter().all(|&c| c < 80));
    let yellow = pixels.iter().any(|p| p[0] > 150 && p[1] > 150 && p[2] < 80);
    assert!(dark, "no dark table pixel");
    assert!(yellow, "no yellow object pixel");
    assert!(pixels.iter().any(|p| p != &pixels[0]), "constant frame");
}

#[wasm_bindgen_test]
fn stepping_matches_run_episode() {
    let ep = run_episode("move".into(), 3.0, 64).unwrap();
    let mut sim = Simulator::new("move".into(), 3.0, 64).unwrap();
    assert_eq!(
        (sim.steps(), sim.step_index(), sim.image_size()),
        (ep.steps(), 0, 64)
    );
    let mut k = 0;
    loop {
        assert_eq!(sim.joints(), ep.joints()[k * 7..(k + 1) * 7]);
        assert_eq!(sim.endpoint(), ep.endpoint()[k * 7..(k + 1) * 7]);
        assert_eq!(sim.object(), ep.object()[k * 3..(k + 1) * 3]);
        if k % 20 == 0 {
            assert_eq!(sim.frame(), ep.frame(k).unwrap());
        }
        if !sim.step() {
            break;
        }
        k += 1;
        assert_eq!(sim.step_index(), k);
    }
    assert_eq!(k + 1, ep.steps());
    assert!(!sim.step());
}

#[wasm_bindgen_test]
fn with_object_places_the_object() {
    let sim = Simulator::with_object("grasp".into(), 0.05, 0.5, 1.0, 128).unwrap();
    let [x, y, _] = sim.object()[..] else {
        panic!("object has 3 values")
    };
    assert!(
        (x - 0.05).abs() < 0.01 && (y - 0.5).abs() < 0.01,
        "object at ({x}, {y})"
    );
    assert_eq!(sim.image_size(), 128);
}

#[wasm_bindgen_test]
fn placement_region_is_a_plain_object() {
    let region = placement_region().unwrap();
    let x = js_sys::Reflect::get(&region, &"x".into()).unwrap();
    let x: Vec<f64> = js_sys::Array::from(&x)
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(x, [-0.15, 0.15]);
}

#[wasm_bindgen_test]
fn bad_arguments_throw() {
    let unknown = message(Simulator::new("jump".into(), 0.0, 64).err().unwrap());
    assert!(unknown.contains("unknown action"), "{unknown}");
    let not_string = message(run_episode(3.into(), 0.0, 64).err().unwrap());
    assert!(
        not_string.contains("action must be a string"),
        "{not_string}"
    );
    let size = message(run_episode("grasp".into(), 0.0, 100).err().unwrap());
    assert!(size.contains("image size 100"), "{size}");
    for seed in [-1.0, 0.5, f64::NAN, f64::INFINITY, 2f64.powi(54)] {
        let err = message(run_episode("grasp".into(), seed, 64).err().unwrap());
        assert!(err.contains("seed"), "{err}");
    }
    for (x, y) in [(1.0, 0.5), (0.0, 0.0), (f32::NAN, 0.5)] {
        let err = message(
            Simulator::with_object("move".into(), x, y, 0.0, 64)
                .err()
                .unwrap(),
        );
        assert!(err.contains("outside the placement region"), "{err}");
    }
    let ep = grasp7();
    let err = message(ep.frame(ep.steps()).err().unwrap());
    assert!(err.contains("out of range"), "{err}");
}
