//! The wasm bindings under node (`wasm-pack test --node`): same episodes as native, usable
//! frames, and bad arguments as JS exceptions rather than traps. Compiles to nothing natively.
#![cfg(target_arch = "wasm32")]

mod golden;
#[path = "golden/futures.rs"]
mod golden_futures;
#[path = "golden/imitation.rs"]
mod golden_imitation;
#[path = "golden/prediction.rs"]
mod golden_prediction;
#[path = "golden/score.rs"]
mod golden_score;

use dmbn::web::{
    enact, heat_map, perform, perform_on_arm, placement_region, replay, run_episode, Episode,
    Folder, ModelHandle, Prediction, Simulator,
};
use wasm_bindgen::{JsError, JsValue};
use wasm_bindgen_test::wasm_bindgen_test;

/// The message of a JS exception, to check it says what was wrong.
fn message(err: JsError) -> String {
    js_sys::Error::from(JsValue::from(err)).message().into()
}

// Arguments as JS passes them (strings as `"grasp".into()`).

fn num(n: f64) -> JsValue {
    JsValue::from_f64(n)
}

fn idx(k: usize) -> JsValue {
    num(k as f64)
}

fn u8s(v: &[u8]) -> JsValue {
    js_sys::Uint8Array::from(v).into()
}

fn f32s(v: &[f32]) -> JsValue {
    js_sys::Float32Array::from(v).into()
}

fn u32s(v: &[u32]) -> JsValue {
    js_sys::Uint32Array::from(v).into()
}

/// An array of strings.
fn strs<S: AsRef<str>>(v: &[S]) -> JsValue {
    v.iter()
        .map(|s| JsValue::from(s.as_ref()))
        .collect::<js_sys::Array>()
        .into()
}

fn grasp7() -> Episode {
    run_episode("grasp".into(), num(7.0), num(64.0)).expect("valid arguments")
}

#[wasm_bindgen_test]
fn digest_matches_native_golden() {
    assert_eq!(grasp7().digest(), golden::GOLDEN_GRASP_SEED7_64);
}

#[wasm_bindgen_test]
fn the_second_arm_simulates_and_performs_as_natively() {
    let panda = || Simulator::new_with_arm("move".into(), num(7.0), num(64.0), "panda".into());
    let sim = panda().unwrap();
    assert_eq!(sim.arm(), "panda");
    let ep = sim.run();
    assert_eq!(ep.joint_count(), 8);
    assert_eq!(ep.digest(), golden::GOLDEN_PANDA_MOVE_SEED7_64);
    let object = ep.object();
    let (x, y) = (num(object[0].into()), num(object[1].into()));
    let replay = perform_on_arm(
        f32s(&ep.joints()),
        x.clone(),
        y.clone(),
        num(64.0),
        "panda".into(),
    );
    assert_eq!(
        replay.unwrap().digest(),
        golden::GOLDEN_PANDA_MOVE_SEED7_REPLAY
    );
    // Rows of the UR5's width are not the Panda's; an arm no one has is named.
    let ur5 = grasp7().joints();
    let err = message(
        perform_on_arm(
            f32s(&ur5[..14]),
            x.clone(),
            y.clone(),
            num(64.0),
            "panda".into(),
        )
        .err()
        .unwrap(),
    );
    assert!(err.contains("rows of 8"), "{err}");
    let err = message(
        perform_on_arm(f32s(&ep.joints()), x, y, num(64.0), "kuka".into())
            .err()
            .unwrap(),
    );
    assert!(err.contains(r#""ur5" or "panda""#), "{err}");
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
        ep.frame(idx(t - 1)).unwrap(),
        ep.frames()[(t - 1) * 64 * 64 * 3..]
    );
}

#[wasm_bindgen_test]
fn frame_shows_table_and_yellow_object() {
    let ep = grasp7();
    let frame = ep.frame(idx(0)).unwrap();
    let pixels: Vec<&[u8]> = frame.chunks(3).collect();
    let dark = pixels.iter().any(|p| p.iter().all(|&c| c < 80));
    let yellow = pixels.iter().any(|p| p[0] > 150 && p[1] > 150 && p[2] < 80);
    assert!(dark, "no dark table pixel");
    assert!(yellow, "no yellow object pixel");
    assert!(pixels.iter().any(|p| p != &pixels[0]), "constant frame");
}

#[wasm_bindgen_test]
fn stepping_matches_run_episode() {
    let ep = run_episode("move".into(), num(3.0), num(64.0)).unwrap();
    let mut sim = Simulator::new("move".into(), num(3.0), num(64.0)).unwrap();
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
            assert_eq!(sim.frame(), ep.frame(idx(k)).unwrap());
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
    let sim =
        Simulator::with_object("grasp".into(), num(0.05), num(0.5), num(1.0), num(128.0)).unwrap();
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
    let unknown = message(
        Simulator::new("jump".into(), num(0.0), num(64.0))
            .err()
            .unwrap(),
    );
    assert!(
        unknown.contains(r#"action must be "grasp" or "move", got "jump""#),
        "{unknown}"
    );
    let not_string = message(run_episode(num(3.0), num(0.0), num(64.0)).err().unwrap());
    assert!(
        not_string.contains(r#"action must be "grasp" or "move", got the number 3"#),
        "{not_string}"
    );
    let size = message(
        run_episode("grasp".into(), num(0.0), num(100.0))
            .err()
            .unwrap(),
    );
    assert!(size.contains("image size 100"), "{size}");
    for seed in [-1.0, 0.5, f64::NAN, f64::INFINITY, 2f64.powi(54)] {
        let err = message(
            run_episode("grasp".into(), num(seed), num(64.0))
                .err()
                .unwrap(),
        );
        assert!(err.contains("seed must be an integer"), "{err}");
    }
    let with_object = |x: f64, y: f64| {
        let sim = Simulator::with_object("move".into(), num(x), num(y), num(0.0), num(64.0));
        message(sim.err().unwrap())
    };
    // Outside `placementRegion()`, named by the coordinate.
    for (x, y, name) in [(1.0, 0.5, "x"), (0.0, 0.0, "y"), (f64::NAN, 0.5, "x")] {
        let err = with_object(x, y);
        assert!(
            err.starts_with(&format!("{name} must be a number in")),
            "{err}"
        );
    }
    let ep = grasp7();
    let err = message(ep.frame(idx(ep.steps())).err().unwrap());
    assert!(err.contains("out of range"), "{err}");
}

/// The golden prediction's inputs as the page passes them: observed frames, joints and times.
fn observed(ep: &Episode) -> (Vec<u8>, Vec<f32>, Vec<f32>) {
    observed_at(ep, &golden_prediction::OBSERVE)
}

/// Steps `steps` of `ep` as the page passes them: frames, joints and times.
fn observed_at(ep: &Episode, steps: &[usize]) -> (Vec<u8>, Vec<f32>, Vec<f32>) {
    let n = 64 * 64 * 3;
    let (frames, joints, times) = (ep.frames(), ep.joints(), ep.times());
    (
        steps
            .iter()
            .flat_map(|&k| frames[k * n..(k + 1) * n].to_vec())
            .collect(),
        steps
            .iter()
            .flat_map(|&k| joints[k * 7..(k + 1) * 7].to_vec())
            .collect(),
        steps.iter().map(|&k| times[k]).collect(),
    )
}

fn golden_prediction() -> (Episode, Prediction) {
    let model =
        ModelHandle::from_bytes(u8s(golden_prediction::MODEL)).expect("shipped weights load");
    assert_eq!(model.kind(), "dmbn");
    assert_eq!(model.image_size(), 64);
    let ep = run_episode(
        "grasp".into(),
        num(golden_prediction::SEED as f64),
        num(64.0),
    )
    .unwrap();
    let (frames, joints, times) = observed(&ep);
    let prediction = model
        .predict(
            u8s(&frames),
            f32s(&joints),
            f32s(&times),
            f32s(&ep.times()),
            num(golden_prediction::BLEND.into()),
        )
        .expect("valid inputs");
    (ep, prediction)
}

#[wasm_bindgen_test]
fn sampled_futures_match_native_within_1e_4() {
    let model = ModelHandle::from_bytes(u8s(golden_futures::MODEL)).unwrap();
    let ep = run_episode("move".into(), num(golden_futures::SEED as f64), num(64.0)).unwrap();
    let steps = dmbn::imitate::Task::Finish.steps(ep.steps(), 5).unwrap();
    let (frames, joints, times) = observed_at(&ep, &steps.observed);
    let contexts = model
        .encode_contexts(u8s(&frames), f32s(&joints), f32s(&times))
        .unwrap();
    let sample = |samples: f64, seed: f64| {
        model.sample(
            &contexts,
            f32s(&ep.times()),
            num(golden_futures::BLEND.into()),
            num(samples),
            num(seed),
        )
    };
    let got = sample(
        golden_futures::SAMPLES as f64,
        golden_futures::SAMPLE_SEED as f64,
    )
    .unwrap();
    let want = golden_futures::expected();
    assert_eq!(got.len(), golden_futures::SAMPLES * ep.steps() * 7);
    let (diff, at) = golden_prediction::max_diff(&got, &want);
    assert!(
        diff < 1e-4,
        "wasm and native futures differ by {diff} at {at}"
    );
    let err = message(sample(0.0, 1.0).err().unwrap());
    assert!(err.contains("samples"), "{err}");
}

#[wasm_bindgen_test]
fn prediction_matches_native_within_1e_4() {
    let (ep, p) = golden_prediction();
    assert_eq!(p.steps(), ep.steps());
    let sample = golden_prediction::sample(p.inner());
    let (diff, at) = golden_prediction::max_diff(&sample, &golden_prediction::expected());
    assert!(
        diff < 1e-4,
        "wasm and native differ by {diff} at sample index {at}"
    );
}

#[wasm_bindgen_test]
fn prediction_arrays_have_sequence_shapes() {
    let (ep, p) = golden_prediction();
    let (t, px) = (ep.steps(), 64 * 64 * 3);
    assert_eq!(p.image_mean().len(), t * px);
    assert_eq!(p.image_sigma().len(), t * px);
    assert_eq!(p.mean_frames().len(), t * px);
    assert_eq!(p.pixel_sigma().len(), t * px / 3);
    assert_eq!(p.joint_mean().len(), t * 7);
    assert_eq!(p.joint_sigma().len(), t * 7);
    assert!(p.max_image_sigma() > 0.0);
    assert_eq!(p.mean_frame(idx(0)).unwrap().len(), px);
    assert_eq!(
        p.sigma_map(idx(t - 1), num(p.max_image_sigma().into()))
            .unwrap()
            .len(),
        px
    );
    assert!(message(p.mean_frame(idx(t)).err().unwrap()).contains("out of range"));
}

#[wasm_bindgen_test]
fn bad_model_input_throws() {
    let bytes = golden_prediction::MODEL;
    let err = message(ModelHandle::from_bytes(u8s(&bytes[..1000])).err().unwrap());
    assert!(err.contains("truncated"), "{err}");
    let err = message(
        ModelHandle::from_bytes(u8s(b"not a model at all"))
            .err()
            .unwrap(),
    );
    assert!(err.contains("not a dmbn model file"), "{err}");

    let model = ModelHandle::from_bytes(u8s(bytes)).unwrap();
    let ep = grasp7();
    let (frames, joints, times) = observed(&ep);
    let (joints, times, targets) = (f32s(&joints), f32s(&times), f32s(&[0.0, 0.5]));
    let err = message(
        model
            .predict(
                u8s(&frames[..100]),
                joints.clone(),
                times.clone(),
                targets.clone(),
                num(0.5),
            )
            .err()
            .unwrap(),
    );
    assert!(err.contains("frames"), "{err}");
    let err = message(
        model
            .predict(u8s(&[]), f32s(&[]), f32s(&[]), targets.clone(), num(0.5))
            .err()
            .unwrap(),
    );
    assert!(err.contains("at least one observed step"), "{err}");
    let err = message(
        model
            .predict(u8s(&frames), joints, times, targets, num(1.5))
            .err()
            .unwrap(),
    );
    assert!(err.contains("blend must be a number in [0, 1]"), "{err}");
}

#[wasm_bindgen_test]
fn eval_sequences_t_p_f() {
    let ep = grasp7();
    let none = || JsValue::UNDEFINED;
    let t = ep
        .eval_sequence("t".into(), num(0.0), none(), none())
        .unwrap();
    assert_eq!((t.frames(), t.times()), (ep.frames(), ep.times()));
    let p = ep
        .eval_sequence("p".into(), num(3.0), none(), none())
        .unwrap();
    assert_eq!(p.frames(), ep.frames());
    assert_ne!(p.times(), ep.times());
    let f = ep
        .eval_sequence("f".into(), num(0.0), idx(10), idx(20))
        .unwrap();
    let n = 64 * 64 * 3;
    assert_eq!(f.frames()[15 * n..16 * n], ep.frames()[10 * n..11 * n]);
    assert_eq!(f.times(), ep.times());
    let err = message(
        ep.eval_sequence("x".into(), num(0.0), none(), none())
            .err()
            .unwrap(),
    );
    assert!(
        err.contains(r#"mode must be "t", "p" or "f", got "x""#),
        "{err}"
    );
}

/// The largest difference between two arrays of the same length.
fn max_diff<T: Copy + Into<f32>>(a: &[T], b: &[T]) -> f32 {
    assert_eq!(a.len(), b.len(), "lengths");
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x.into() - y.into()).abs())
        .fold(0.0, f32::max)
}

/// The page's way (its workers `decode` in chunks of 10; it scales by the largest
/// `maxImageSigma` of the chunks and colours with `heatMap`) gives what `predict` gives, σ
/// heat maps included: those of `sigmaMap`, the code `dmbn predict` writes its σ images with.
#[wasm_bindgen_test]
fn encode_then_decode_in_chunks_matches_predict() {
    let (ep, p) = golden_prediction();
    let m = ModelHandle::from_bytes(u8s(golden_prediction::MODEL)).unwrap();
    let (frames, joints, times) = observed(&ep);
    let encoding = m
        .encode(
            u8s(&frames),
            f32s(&joints),
            f32s(&times),
            num(golden_prediction::BLEND.into()),
        )
        .unwrap();
    let chunks: Vec<Prediction> = ep
        .times()
        .chunks(10)
        .map(|chunk| m.decode(&encoding, f32s(chunk)).unwrap())
        .collect();
    let cat = |part: fn(&Prediction) -> Vec<f32>| chunks.iter().flat_map(part).collect::<Vec<_>>();
    assert_eq!(
        chunks.iter().map(Prediction::steps).sum::<usize>(),
        ep.steps()
    );
    for (what, part) in [
        (
            "joint mean",
            Prediction::joint_mean as fn(&Prediction) -> Vec<f32>,
        ),
        ("joint σ", Prediction::joint_sigma),
        ("pixel σ", Prediction::pixel_sigma),
    ] {
        let diff = max_diff(&cat(part), &part(&p));
        assert!(
            diff < 1e-4,
            "{what}: encode/decode and predict differ by {diff}"
        );
    }
    let means: Vec<u8> = chunks.iter().flat_map(Prediction::mean_frames).collect();
    assert!(max_diff(&means, &p.mean_frames()) <= 1.0, "mean frames");

    let max = p.max_image_sigma();
    let maxima = chunks.iter().map(Prediction::max_image_sigma);
    let scale = golden_prediction::page_scale(maxima, max, 1e-4);
    let (sigma, whole, px) = (cat(Prediction::pixel_sigma), p.pixel_sigma(), 64 * 64);
    for k in 0..ep.steps() {
        let cli = p.sigma_map(idx(k), num(max.into())).unwrap();
        let whole_map = heat_map(f32s(&whole[k * px..(k + 1) * px]), num(max.into())).unwrap();
        assert_eq!(whole_map, cli, "step {k}");
        let page = heat_map(f32s(&sigma[k * px..(k + 1) * px]), num(scale.into())).unwrap();
        assert!(
            max_diff(&page, &cli) <= 1.0,
            "step {k}: the page's heat map"
        );
    }
}

/// The worker's way in live mode: each observation encoded once (`encodeContexts`), the sets
/// joined (`cat`) or cut (`select`), then `represent` and `decode`, gives what `predict` gives.
#[wasm_bindgen_test]
fn encoded_contexts_joined_and_selected_predict_as_predict() {
    let (ep, p) = golden_prediction();
    let m = ModelHandle::from_bytes(u8s(golden_prediction::MODEL)).unwrap();
    let (frames, joints, times) = observed(&ep);
    let (n, blend) = (64 * 64 * 3, num(golden_prediction::BLEND.into()));
    let one = |i: usize| {
        m.encode_contexts(
            u8s(&frames[i * n..(i + 1) * n]),
            f32s(&joints[i * 7..(i + 1) * 7]),
            f32s(&times[i..i + 1]),
        )
        .unwrap()
    };
    // Encoded in the order 2, 0, 1, then put back in order.
    let set = one(2).cat(&one(0)).unwrap().cat(&one(1)).unwrap();
    assert_eq!(set.len(), 3);
    let ordered = set.select(u32s(&[1, 2, 0])).unwrap();
    let encoding = m.represent(&ordered, blend.clone()).unwrap();
    let q = m.decode(&encoding, f32s(&ep.times())).unwrap();
    for (what, part) in [
        (
            "joint mean",
            Prediction::joint_mean as fn(&Prediction) -> Vec<f32>,
        ),
        ("joint σ", Prediction::joint_sigma),
        ("image mean", Prediction::image_mean),
        ("image σ", Prediction::image_sigma),
    ] {
        let diff = max_diff(&part(&q), &part(&p));
        assert!(
            diff < 1e-4,
            "{what}: encoded contexts and predict differ by {diff}"
        );
    }
    assert!(message(set.select(u32s(&[3])).err().unwrap()).contains("out of range"));
    assert!(message(m.represent(&set, num(2.0)).err().unwrap()).contains("blend must be"));
    let other = ModelHandle::from_bytes(u8s(golden_prediction::MODEL)).unwrap();
    let theirs = other
        .encode_contexts(u8s(&frames[..n]), f32s(&joints[..7]), f32s(&times[..1]))
        .unwrap();
    assert!(message(m.represent(&theirs, blend).err().unwrap()).contains("another model"));
    assert!(message(set.cat(&theirs).err().unwrap()).contains("another model"));
}

#[wasm_bindgen_test]
fn scores_match_native_within_1e_4() {
    #[derive(serde::Deserialize)]
    struct Scores {
        model: dmbn::quality::Quality,
        baseline: dmbn::quality::Quality,
    }
    let model = ModelHandle::from_bytes(u8s(golden_score::MODEL)).unwrap();
    let ep = run_episode("grasp".into(), num(golden_score::SEED as f64), num(64.0)).unwrap();
    let expected = golden_score::expected();
    assert_eq!(expected.len(), golden_score::SCENARIOS.len());
    for (scenario, want) in golden_score::SCENARIOS.iter().zip(&expected) {
        let value = model
            .score(
                &ep,
                scenario.name().into(),
                idx(golden_score::OBSERVATIONS),
                num(golden_score::BLEND.into()),
            )
            .expect("valid arguments");
        let scores: Scores = serde_wasm_bindgen::from_value(value).expect("{model, baseline}");
        // The model's σ is judged (the calibration compared in the sample), a baseline has none.
        assert!(scores.model.calibration.is_some() && scores.baseline.calibration.is_none());
        let got = golden_score::sample(&scores.model, &scores.baseline);
        let (diff, at) = golden_score::max_diff(&got, want);
        assert!(
            diff < 1e-4,
            "{scenario}: wasm and native differ by {diff} at {at}"
        );
    }
    let err = model
        .score(&ep, "all".into(), num(5.0), num(0.5))
        .map(|_| ())
        .unwrap_err();
    let err = message(err);
    assert!(
        err.contains(r#"scenario must be "interp" or "extrap", got "all""#),
        "{err}"
    );
}

#[wasm_bindgen_test]
fn forecast_error_scores_drawn_frames_and_names_bad_layouts() {
    let ep = grasp7();
    let (frames, joints) = (ep.frames(), ep.joints());
    let forecast_error = |true_frames: &[u8], frames: &[u8]| {
        // No joint count: the simulator arm's 7, as the page passed them before it had one.
        dmbn::web::forecast_error(
            u8s(true_frames),
            f32s(&joints),
            u8s(frames),
            f32s(&joints),
            JsValue::UNDEFINED,
        )
    };
    let quality = |value: JsValue| -> dmbn::quality::Quality {
        serde_wasm_bindgen::from_value(value).expect("the fields of dmbn score --json")
    };
    let exact = quality(forecast_error(&frames, &frames).unwrap());
    assert_eq!(exact.steps, ep.steps());
    // (The page's bytes become values in [0, 1] in f32, the truth in f64.)
    assert!(
        exact.joint_rmse == 0.0 && exact.image_mse < 1e-12,
        "{exact:?}"
    );
    // Every frame one step late: the error of holding each frame a step too long.
    let px = 64 * 64 * 3;
    let late: Vec<u8> = [&frames[..px], &frames[..frames.len() - px]].concat();
    let lagged = quality(forecast_error(&frames, &late).unwrap());
    assert!(
        lagged.image_mse > 1e-5 && lagged.joint_rmse == 0.0,
        "{lagged:?}"
    );
    let err = forecast_error(&frames, &frames[1..]).unwrap_err();
    assert!(message(err).contains("frames:"));
}

/// The files of `ep` as sequence 7 of grasp in a folder `mine/`, as the page hands them over:
/// (relative path, bytes), frames as PNG, rows as `dmbn simulate` writes them.
fn folder_files(ep: &Episode) -> Vec<(String, Vec<u8>)> {
    use image::{codecs::png::PngEncoder, ExtendedColorType, ImageEncoder};
    let table = |values: Vec<f32>, width: usize| -> Vec<u8> {
        let rows: Vec<String> = values
            .chunks(width)
            .map(|r| r.iter().map(f32::to_string).collect::<Vec<_>>().join(" "))
            .collect();
        (rows.join("\n") + "\n").into_bytes()
    };
    let mut files = vec![
        (
            "mine/7/grasp/joint_7.txt".to_string(),
            table(ep.joints(), 7),
        ),
        (
            "mine/7/grasp/object_7.txt".to_string(),
            table(ep.object(), 3),
        ),
        (
            "mine/7/grasp/endpoint_7.txt".to_string(),
            table(ep.endpoint(), 7),
        ),
        ("mine/LICENSE".to_string(), b"MIT".to_vec()),
    ];
    for k in 0..ep.steps() {
        let mut png = Vec::new();
        PngEncoder::new(&mut png)
            .write_image(&ep.frame(idx(k)).unwrap(), 64, 64, ExtendedColorType::Rgb8)
            .unwrap();
        files.push((format!("mine/7/grasp/{k}.png"), png));
    }
    files
}

/// The paths of `files`, as the page lists a folder.
fn paths(files: &[(String, Vec<u8>)]) -> JsValue {
    let paths: Vec<&str> = files.iter().map(|f| f.0.as_str()).collect();
    strs(&paths)
}

/// A folder of `files`, listed, its sequence 7 read at 64 px: the episode's digest.
fn read_folder(files: &[(String, Vec<u8>)]) -> Result<String, String> {
    let mut folder = Folder::new(paths(files)).map_err(message)?;
    for path in folder.files_of(num(7.0), "grasp".into()).map_err(message)? {
        let (_, bytes) = files.iter().find(|f| f.0 == path).unwrap();
        folder.put(path.into(), u8s(bytes)).map_err(message)?;
    }
    folder
        .read(num(7.0), "grasp".into(), num(64.0))
        .map(|e| e.digest())
        .map_err(message)
}

#[wasm_bindgen_test]
fn folder_reads_a_sequence_as_written_and_reports_the_readers_errors() {
    let ep = grasp7();
    let mut files = folder_files(&ep);
    assert_eq!(read_folder(&files).unwrap(), ep.digest());
    let mut folder = Folder::new(paths(&files)).unwrap();
    assert_eq!(folder.root(), "mine");
    let err = message(
        folder
            .put("mine/7/grasp/extra.txt".into(), u8s(b"1"))
            .unwrap_err(),
    );
    assert!(err.contains("path must be a file of this folder"), "{err}");

    files[0].1 = b"1 2 3 4 5 6 7\n1 2 x\n".to_vec();
    assert_eq!(
        read_folder(&files).unwrap_err(),
        "mine/7/grasp/joint_7.txt line 2: expected 7 columns, found 3"
    );
    let err = read_folder(&files[1..]).unwrap_err();
    assert_eq!(err, "mine/7/grasp/joint_7.txt: no such file");
    let err = read_folder(&files[3..4]).unwrap_err();
    assert!(err.starts_with("mine: no sequences found"), "{err}");
    let err = Folder::new(strs(&["a/0/grasp/x", "b/0/grasp/y"]))
        .map(|_| ())
        .map_err(message);
    assert_eq!(
        err.unwrap_err(),
        "expected the files of one folder, found a/ and b/"
    );

    // The joints of the episode lie 0 standard deviations from their own mean.
    let joints = ep.joints();
    let mean: Vec<f32> = (0..7)
        .map(|j| joints.iter().skip(j).step_by(7).sum::<f32>() / ep.steps() as f32)
        .collect();
    let ones = f32s(&[1.0; 7]);
    let near = ep.joint_distance(f32s(&mean), ones.clone()).unwrap();
    let shifted: Vec<f32> = mean.iter().map(|m| m + 3.0).collect();
    let far = ep.joint_distance(f32s(&shifted), ones.clone()).unwrap();
    assert!(
        near < far && (far - 9.0 - near).abs() < 1e-3,
        "{near} {far}"
    );
    let err = message(ep.joint_distance(f32s(&[0.0; 6]), ones).unwrap_err());
    assert!(
        err.contains("mean must be a Float32Array of 7 values"),
        "{err}"
    );
}

/// `Model.imitate` against the native golden: the same trajectory within 1e-4 and the same
/// outcome; the simulator performs the golden trajectories and the replay bit for bit.
#[wasm_bindgen_test]
fn imitation_matches_native() {
    let golden = golden_imitation::expected();
    let model = ModelHandle::from_bytes(u8s(golden_imitation::MODEL)).unwrap();
    let action = golden_imitation::ACTION.name();
    let ep = run_episode(action.into(), num(golden_imitation::SEED as f64), num(64.0)).unwrap();
    for ((task, blend), want) in [("frames", 1.0), ("finish", 0.5)].iter().zip(&golden.tasks) {
        let i = model
            .imitate(&ep, action.into(), (*task).into(), num(5.0), num(*blend))
            .unwrap()
            .expect("long enough");
        let outcome: serde_json::Value =
            serde_wasm_bindgen::from_value(i.outcome().unwrap()).unwrap();
        let f = |k: &str| outcome[k].as_f64().unwrap() as f32;
        let got = golden_imitation::Sample {
            trajectory: i.trajectory(),
            success: outcome["success"].as_bool().unwrap(),
            lift_cm: f("lift_cm"),
            object_error_cm: f("object_error_cm"),
            path_error_cm: f("path_error_cm"),
            performance_digest: i.performance().digest(),
        };
        golden_imitation::assert_agrees(&got, want, 1e-4);
        assert!(outcome["summary"].as_str().unwrap().len() > 5);
        // The same trajectory performed here is the native performance, bit for bit.
        let object = ep.object();
        let (x, y) = (num(object[0].into()), num(object[1].into()));
        let performed = perform(f32s(&want.trajectory), x, y, num(64.0)).unwrap();
        assert_eq!(performed.digest(), want.performance_digest);
        // And enacted against the demonstration (the page's path), judged as natively.
        let trajectory = f32s(&want.trajectory);
        let e = enact(&ep, action.into(), trajectory, u32s(&i.observed())).unwrap();
        assert_eq!(e.performance().digest(), want.performance_digest);
        let outcome: serde_json::Value =
            serde_wasm_bindgen::from_value(e.outcome().unwrap()).unwrap();
        assert_eq!(outcome["success"].as_bool().unwrap(), want.success);
        assert_eq!(e.observed(), i.observed());
    }
    let r = replay(&ep, action.into()).unwrap();
    assert_eq!(r.performance().digest(), golden.replay_digest);
    let outcome: serde_json::Value = serde_wasm_bindgen::from_value(r.outcome().unwrap()).unwrap();
    assert!(outcome["push_error_cm"].is_null(), "a grasp: {outcome}");
    // A push that never leaves home: short by the demonstration's travel, said in the summary.
    let push = run_episode("move".into(), num(5.0), num(64.0)).unwrap();
    let home: Vec<f32> = (0..push.joints().len() / 7)
        .flat_map(|_| push.joints()[..7].to_vec())
        .collect();
    let e = enact(&push, "move".into(), f32s(&home), u32s(&[])).unwrap();
    let outcome: serde_json::Value = serde_wasm_bindgen::from_value(e.outcome().unwrap()).unwrap();
    let along = outcome["push_error_cm"]["along"].as_f64().unwrap();
    assert!(along < -5.0, "{outcome}");
    assert!(outcome["push_error_cm"]["across"].is_number(), "{outcome}");
    let summary = outcome["summary"].as_str().unwrap();
    assert!(summary.contains("cm short"), "{summary}");
    assert_eq!(r.observed(), Vec::<u32>::new());
    assert_eq!(r.joint_rmse(), 0.0);
}

#[wasm_bindgen_test]
fn bad_imitation_arguments_throw() {
    let model = ModelHandle::from_bytes(u8s(golden_imitation::MODEL)).unwrap();
    let ep = grasp7();
    let imitate = |action: JsValue, task: JsValue, observations: f64, blend: f64| {
        let imitation = model.imitate(&ep, action, task, num(observations), num(blend));
        message(imitation.err().unwrap())
    };
    let err = imitate(num(3.0), "frames".into(), 5.0, 1.0);
    assert!(
        err.contains(r#"action must be "grasp" or "move", got the number 3"#),
        "{err}"
    );
    let err = imitate("grasp".into(), num(3.0), 5.0, 1.0);
    assert!(
        err.contains(r#"task must be "frames" or "finish", got the number 3"#),
        "{err}"
    );
    let err = imitate("grasp".into(), "interp".into(), 5.0, 1.0);
    assert!(
        err.contains(r#"task must be "frames" or "finish", got "interp""#),
        "{err}"
    );
    for k in [1.0, 2.5, -1.0, f64::NAN, f64::INFINITY, 2f64.powi(53)] {
        let err = imitate("grasp".into(), "frames".into(), k, 1.0);
        assert!(err.contains("observations must be an integer"), "{err}");
    }
    let err = imitate("grasp".into(), "frames".into(), 5.0, 2.0);
    assert!(err.contains("blend must be"), "{err}");
    let bad = |t: &[f32]| {
        message(
            perform(f32s(t), num(0.0), num(0.5), num(64.0))
                .err()
                .unwrap(),
        )
    };
    assert!(bad(&[0.0; 13]).contains("13 values"));
    assert!(bad(&[]).contains("no rows"));
    assert!(bad(&[f32::NAN; 7]).contains("NaN"));
    assert!(bad(&[9.0; 7]).contains("joint limits"));
    let ok = ep.joints();
    let err = message(
        perform(f32s(&ok), num(5.0), num(0.5), num(64.0))
            .err()
            .unwrap(),
    );
    assert!(err.starts_with("x must be a number in"), "{err}");
    let err = message(replay(&ep, "jump".into()).err().unwrap());
    assert!(
        err.contains(r#"action must be "grasp" or "move", got "jump""#),
        "{err}"
    );
    let enacted = |t: &[f32], observed: &[u32]| enact(&ep, "grasp".into(), f32s(t), u32s(observed));
    assert!(message(enacted(&ok[..70], &[]).err().unwrap()).contains("rows"));
    assert!(message(enacted(&[f32::NAN; 7], &[]).err().unwrap()).contains("NaN"));
    assert!(message(enacted(&ok, &[0, 9999]).err().unwrap()).contains("observed step 9999"));
    assert!(enacted(&ok, &[0, 10]).unwrap().outcome().is_ok());
    // Still usable afterwards.
    assert!(model
        .imitate(&ep, "grasp".into(), "frames".into(), num(5.0), num(1.0))
        .unwrap()
        .is_some());
}
