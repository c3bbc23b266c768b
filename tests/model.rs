//! DMBN and DMBN-PTE: output shapes, encode-once/decode-many, training on one tiny batch,
//! the model file (round trips and every kind of bad file) and bad batches. Native only
//! (training needs autodiff and an optimiser).
#![cfg(not(target_arch = "wasm32"))]

use std::sync::Mutex;

use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::{Device, Tensor, TensorData};
use dmbn::augment::Batch;
use dmbn::data::{write_atomic, JOINTS};
use dmbn::model::{
    file, load_bytes, load_bytes_expecting, read_header, save_bytes, tensors,
    with_joint_sigma_scale, BatchTensors, JointSigmaScale, Model, ModelConfig, ModelError,
    ModelKind, Normalization, Prediction, Representation,
};

/// A small deterministic pseudo-random generator (values in [0, 1)).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }

    fn fill(&mut self, len: usize, scale: f32, offset: f32) -> Vec<f32> {
        (0..len).map(|_| self.next() * scale + offset).collect()
    }
}

/// A batch with smooth-ish frames and joints; the last sequence (when B > 1) uses only its
/// first context slot, the others are padding.
fn batch(b: usize, n: usize, m: usize, s: usize, seed: u64) -> Batch {
    let mut rng = Lcg(seed);
    let mut context_mask = vec![1.0; b * n];
    if b > 1 {
        for slot in 1..n {
            context_mask[(b - 1) * n + slot] = 0.0;
        }
    }
    Batch {
        batch: b,
        contexts: n,
        targets: m,
        image_size: s,
        joints: 7,
        context_images: rng.fill(b * n * 3 * s * s, 1.0, 0.0),
        context_joints: rng.fill(b * n * 7, 2.0, -1.0),
        context_times: rng.fill(b * n, 1.0, 0.0),
        context_mask,
        target_images: rng.fill(b * m * 3 * s * s, 1.0, 0.0),
        target_joints: rng.fill(b * m * 7, 2.0, -1.0),
        target_times: rng.fill(b * m, 1.0, 0.0),
        blend: rng.fill(b, 1.0, 0.0),
    }
}

fn device() -> Device {
    Device::flex()
}

/// burn's generator is shared by the tests running beside each other: initialisations take
/// turns, each seeded, so every test sees the same weights whatever runs with it.
static INIT: Mutex<()> = Mutex::new(());

fn model(kind: ModelKind, image_size: usize, device: &Device) -> Model {
    init(ModelConfig::new(kind).with_image_size(image_size), device)
}

/// The model `config` describes, with seeded weights drawn.
fn init(config: ModelConfig, device: &Device) -> Model {
    let _turn = INIT.lock().unwrap_or_else(|e| e.into_inner());
    device.seed(7);
    let model = config.init(device).unwrap();
    model.draw_weights();
    model
}

fn values<const D: usize>(t: &Tensor<D>) -> Vec<f32> {
    t.to_data().convert::<f32>().try_to_vec().unwrap()
}

fn max_abs_diff<const D: usize>(a: &Tensor<D>, b: &Tensor<D>) -> f32 {
    assert_eq!(a.dims(), b.dims());
    values(a)
        .iter()
        .zip(values(b))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

fn prediction_diff(a: &Prediction, b: &Prediction) -> f32 {
    [
        max_abs_diff(&a.image_mean, &b.image_mean),
        max_abs_diff(&a.image_sigma, &b.image_sigma),
        max_abs_diff(&a.joint_mean, &b.joint_mean),
        max_abs_diff(&a.joint_sigma, &b.joint_sigma),
    ]
    .into_iter()
    .fold(0.0, f32::max)
}

#[test]
fn output_shapes_for_both_models_and_sizes() {
    let device = device();
    for kind in ModelKind::ALL {
        for (s, (b, n, m)) in [(64, (2, 3, 2)), (128, (1, 2, 1))] {
            let model = model(kind, s, &device);
            let t = tensors(&batch(b, n, m, s, 1), &device).unwrap();
            let p = model.forward(&t).unwrap();
            assert_eq!(p.image_mean.dims(), [b, m, 3, s, s], "{kind} {s}");
            assert_eq!(p.image_sigma.dims(), [b, m, 3, s, s], "{kind} {s}");
            assert_eq!(p.joint_mean.dims(), [b, m, 7], "{kind} {s}");
            assert_eq!(p.joint_sigma.dims(), [b, m, 7], "{kind} {s}");
            let z = model.encode_contexts(&t).unwrap();
            assert_eq!(z.image.dims(), [b, n, 128]);
            assert_eq!(z.joint.dims(), [b, n, 128]);
            let representation = model.encode(&t).unwrap();
            assert_eq!(representation.batch(), b);
            match (kind, representation) {
                (ModelKind::Attn, Representation::Attentive(c)) => {
                    assert_eq!(c.keys.dims(), [b, n, 128]);
                    assert_eq!(c.padding.dims(), [b, n]);
                }
                (ModelKind::Attn, _) => panic!("attn attends"),
                (_, Representation::Mean(r)) => assert_eq!(r.dims(), [b, 128]),
                (_, _) => panic!("{kind} averages"),
            }
            let mean = values(&p.image_mean);
            assert!(mean.iter().all(|v| (0.0..=1.0).contains(v)), "{kind}");
            for sigma in [values(&p.image_sigma), values(&p.joint_sigma)] {
                assert!(sigma.iter().all(|&v| v > 0.01 && v.is_finite()), "{kind}");
            }
        }
    }
}

/// Sequence `i` of `b` alone, as a batch of one.
fn one(b: &Batch, i: usize) -> Batch {
    let (n, m, px) = (b.contexts, b.targets, 3 * b.image_size * b.image_size);
    let rows = |v: &[f32], per: usize| v[i * per..(i + 1) * per].to_vec();
    Batch {
        batch: 1,
        context_images: rows(&b.context_images, n * px),
        context_joints: rows(&b.context_joints, n * 7),
        context_times: rows(&b.context_times, n),
        context_mask: rows(&b.context_mask, n),
        target_images: rows(&b.target_images, m * px),
        target_joints: rows(&b.target_joints, m * 7),
        target_times: rows(&b.target_times, m),
        blend: rows(&b.blend, 1),
        ..b.clone()
    }
}

/// Each sequence of a batch is predicted as if alone (its padded context slots, random here,
/// change nothing), and each target as if decoded alone.
#[test]
fn sequences_and_targets_are_predicted_independently() {
    let device = device();
    for kind in ModelKind::ALL {
        let model = model(kind, 64, &device);
        let b = batch(2, 3, 4, 64, 2);
        let t = tensors(&b, &device).unwrap();
        let whole = model.forward(&t).unwrap();
        for i in 0..2 {
            let alone = model
                .forward(&tensors(&one(&b, i), &device).unwrap())
                .unwrap();
            let row = |x: &Tensor<5>| x.clone().narrow(0, i, 1);
            let joints = whole.joint_mean.clone().narrow(0, i, 1);
            assert!(
                max_abs_diff(&alone.joint_mean, &joints) < 1e-5,
                "{kind} {i}"
            );
            assert!(max_abs_diff(&alone.image_mean, &row(&whole.image_mean)) < 1e-5);
            assert!(max_abs_diff(&alone.image_sigma, &row(&whole.image_sigma)) < 1e-5);
        }
        // The sequences differ, so the test above compares something.
        let first = whole.joint_mean.clone().narrow(0, 0, 1);
        assert!(max_abs_diff(&first, &whole.joint_mean.clone().narrow(0, 1, 1)) > 1e-3);
        // Decoding targets 1..3 alone gives what decoding all four gave for them.
        let r = model.encode(&t).unwrap();
        let part = model
            .decode(&r, t.target_times.clone().slice([0..2, 1..3]))
            .unwrap();
        let joints = whole.joint_mean.clone().slice([0..2, 1..3]);
        assert!(max_abs_diff(&part.joint_mean, &joints) < 1e-5, "{kind}");
        let sigma = whole.image_sigma.clone().slice([0..2, 1..3]);
        assert!(max_abs_diff(&part.image_sigma, &sigma) < 1e-5, "{kind}");
    }
}

/// An attentive model starts from the observations interpolated to the target times: at an
/// observed step it returns the observed joints and frames (its joint correction vanishes
/// there and its image gate is held open, trained or not); a modality the blend leaves out
/// contributes nothing.
#[test]
fn a_fresh_attentive_model_goes_through_its_observations_and_only_the_observed_ones() {
    let device = device();
    let model = model(ModelKind::Attn, 64, &device);
    let mut b = batch(1, 3, 3, 64, 4);
    b.context_times = vec![0.1, 0.5, 0.9];
    b.target_times = b.context_times.clone();
    let predict = |b: &Batch, blend: f32| {
        let mut b = b.clone();
        b.blend = vec![blend];
        let p = model.forward(&tensors(&b, &device).unwrap()).unwrap();
        (values(&p.image_mean), values(&p.joint_mean))
    };
    let rms = |a: &[f32], b: &[f32]| {
        assert_eq!(a.len(), b.len());
        let sum: f32 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        (sum / a.len() as f32).sqrt()
    };
    let (frames, joints) = (&b.context_images, &b.context_joints);
    // Frames only: the frames are copied, the joints are not.
    let (image_1, joints_1) = predict(&b, 1.0);
    // Joints only: the joints are, the frames are not (and do not matter).
    let (image_0, joints_0) = predict(&b, 0.0);
    // Both.
    let (image, joints_half) = predict(&b, 0.5);
    // At an observed step the gate is held open: the observed frames exactly.
    for observed in [&image, &image_1] {
        assert!(rms(observed, frames) < 1e-6, "{}", rms(observed, frames));
    }
    assert!(rms(&image_0, frames) > 0.2, "{}", rms(&image_0, frames));
    // At an observed step the joint correction vanishes: the observed joints exactly.
    for observed in [&joints_half, &joints_0] {
        assert!(rms(observed, joints) < 1e-6, "{}", rms(observed, joints));
    }
    assert!(rms(&joints_1, joints) > 0.1, "{}", rms(&joints_1, joints));
    let mut other = b.clone();
    other.context_images.iter_mut().for_each(|v| *v = 1.0 - *v);
    assert_eq!(predict(&other, 0.0).0, image_0);
}

#[test]
fn padding_slots_do_not_matter() {
    let device = device();
    for kind in ModelKind::ALL {
        let model = model(kind, 64, &device);
        let a = batch(2, 3, 1, 64, 3);
        let mut b = a.clone();
        // Change everything in the padding slots of sequence 1 (slots 1 and 2).
        let frame = 3 * 64 * 64;
        for slot in [4, 5] {
            b.context_images[slot * frame..(slot + 1) * frame].fill(0.5);
            b.context_joints[slot * 7..(slot + 1) * 7].fill(3.0);
            b.context_times[slot] = 0.9;
        }
        let pa = model.forward(&tensors(&a, &device).unwrap()).unwrap();
        let pb = model.forward(&tensors(&b, &device).unwrap()).unwrap();
        assert!(prediction_diff(&pa, &pb) < 1e-6, "{kind}");
    }
}

#[test]
fn loss_is_finite_and_falls_when_overfitting_one_batch() {
    let device = device().autodiff();
    for kind in ModelKind::ALL {
        let mut model = model(kind, 64, &device);
        let t = tensors(&batch(1, 2, 2, 64, 4), &device).unwrap();
        let mut optimizer = AdamConfig::new().init();
        let mut first = None;
        let mut last = f32::NAN;
        let mut mse = (None, f32::NAN);
        for _ in 0..50 {
            let prediction = model.forward(&t).unwrap();
            let loss = model.loss(&prediction, &t, 0.0).unwrap();
            let v = loss.values();
            assert!(v.total.is_finite() && v.image_nll.is_finite() && v.joint_nll.is_finite());
            assert!((v.total - (v.image_nll + 0.01 * v.joint_nll)).abs() < 1e-4);
            first.get_or_insert(v.total);
            last = v.total;
            mse.0.get_or_insert(v.image_mse + v.joint_mse);
            mse.1 = v.image_mse + v.joint_mse;
            let grads = GradientsParams::from_grads(loss.total.backward(), &model);
            model = optimizer.step(1e-3, model, grads);
        }
        let first = first.unwrap();
        eprintln!("{kind}: loss {first} -> {last}");
        assert!(last < first - 0.2, "{kind}: loss {first} -> {last}");
        // Not only σ shrinking: the means move towards the targets.
        let (a, b) = (mse.0.unwrap(), mse.1);
        assert!(b < 0.9 * a, "{kind}: image + joint MSE {a} -> {b}");
    }
}

fn saved(kind: ModelKind, half: bool) -> (Model, Vec<u8>, Normalization) {
    let device = device();
    let model = model(kind, 64, &device);
    let mut normalization = Normalization::identity(JOINTS);
    normalization.mean[0] = 0.5;
    normalization.std[6] = 0.03;
    let bytes = save_bytes(&model, &normalization, half).unwrap();
    (model, bytes, normalization)
}

#[test]
fn save_load_round_trip_exact_in_f32_and_close_in_f16() {
    let device = device();
    let t = tensors(&batch(2, 3, 2, 64, 5), &device).unwrap();
    for kind in ModelKind::ALL {
        let (model, bytes, normalization) = saved(kind, false);
        let expected = model.forward(&t).unwrap();
        let (loaded, norm, config) = load_bytes(&bytes, &device).unwrap();
        assert_eq!(norm, normalization);
        assert_eq!(&config, model.config());
        assert_eq!(loaded.config(), model.config());
        let p = loaded.forward(&t).unwrap();
        assert_eq!(prediction_diff(&expected, &p), 0.0, "{kind} f32");

        let (_, half, _) = {
            let bytes = save_bytes(&model, &normalization, true).unwrap();
            ((), bytes, ())
        };
        assert!(
            half.len() < bytes.len() * 6 / 10,
            "{} vs {}",
            half.len(),
            bytes.len()
        );
        let header = read_header(&half).unwrap();
        assert_eq!(header.weights.dtype, file::WeightDType::F16);
        let (loaded, _, _) = load_bytes(&half, &device).unwrap();
        let p = loaded.forward(&t).unwrap();
        let diff = prediction_diff(&expected, &p);
        assert!(diff > 0.0 && diff < 0.02, "{kind} f16: {diff}");
    }
}

#[test]
fn save_and_load_a_file() {
    let device = device();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pte.dmbn");
    let (model, _, normalization) = saved(ModelKind::Pte, false);
    let bytes = save_bytes(&model, &normalization, false).unwrap();
    write_atomic(&path, &bytes).unwrap();
    // Overwriting works too, and leaves no temporary file behind.
    write_atomic(&path, &bytes).unwrap();
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
    let t = tensors(&batch(1, 2, 1, 64, 6), &device).unwrap();
    let read = std::fs::read(&path).unwrap();
    let (loaded, norm, _) =
        load_bytes_expecting(&read, &device, Some(ModelKind::Pte), Some(64)).unwrap();
    assert_eq!(norm, normalization);
    let diff = prediction_diff(&model.forward(&t).unwrap(), &loaded.forward(&t).unwrap());
    assert_eq!(diff, 0.0);
}

/// The config `bytes` (`model` saved) read back with, after checking that the model read
/// predicts 64x64 frames exactly as `model` does; and that batch and prediction.
fn reads_back_exactly(
    model: &Model,
    bytes: &[u8],
    device: &Device,
) -> (ModelConfig, (BatchTensors, Prediction)) {
    let (loaded, _, config) = load_bytes(bytes, device).unwrap();
    let t = tensors(&batch(1, 2, 2, 64, 8), device).unwrap();
    let p = model.forward(&t).unwrap();
    assert_eq!(p.image_mean.dims(), [1, 2, 3, 64, 64]);
    assert_eq!(prediction_diff(&p, &loaded.forward(&t).unwrap()), 0.0);
    (config, (t, p))
}

#[test]
fn narrow_image_networks_are_saved_with_their_filters() {
    let device = device();
    let narrow = vec![128, 64, 32, 32, 16, 8, 8];
    let encoder = vec![16, 32, 64, 64, 128];
    let config = ModelConfig::new(ModelKind::Attn)
        .with_decoder_filters(Some(narrow.clone()))
        .with_encoder_filters(Some(encoder.clone()));
    let model = init(config, &device);
    let bytes = save_bytes(&model, &Normalization::identity(JOINTS), false).unwrap();
    let (_, full, _) = saved(ModelKind::Attn, false);
    assert!(
        bytes.len() < full.len(),
        "{} vs {}",
        bytes.len(),
        full.len()
    );
    let (config, _) = reads_back_exactly(&model, &bytes, &device);
    assert_eq!(config.decoder_filters, Some(narrow));
    assert_eq!(config.encoder_filters, Some(encoder));
    // A header whose filters do not describe the weights is refused, as are filters that
    // do not fit the frame size.
    let (header, weights) = parts(&bytes);
    for (field, value, config_error) in [
        ("decoder_filters", serde_json::Value::Null, false),
        (
            "decoder_filters",
            serde_json::json!([128, 64, 32, 32, 16, 16, 8]),
            false,
        ),
        ("decoder_filters", serde_json::json!([128, 64, 32]), true),
        ("encoder_filters", serde_json::Value::Null, false),
        (
            "encoder_filters",
            serde_json::json!([16, 32, 64, 64, 64]),
            false,
        ),
        ("encoder_filters", serde_json::json!([16, 32, 64]), true),
    ] {
        let mut header = header.clone();
        header["config"][field] = value.clone();
        let err = load_err(&assemble(&header, &weights));
        match err {
            ModelError::Config { field: f, .. } if config_error => assert_eq!(f, field),
            ModelError::Weights(_) if !config_error => {}
            e => panic!("{field} {value}: {e}"),
        }
    }
}

#[test]
fn a_coarse_tail_is_saved_with_the_model_and_decodes_full_size_frames() {
    let device = device();
    let filters = Some(vec![128, 64, 32, 32, 16, 16, 8]);
    let fine = ModelConfig::new(ModelKind::Attn).with_decoder_filters(filters);
    let coarse = fine.clone().with_coarse_tail(Some(true));
    let model = init(coarse, &device);
    let bytes = save_bytes(&model, &Normalization::identity(JOINTS), false).unwrap();
    let (config, (t, p)) = reads_back_exactly(&model, &bytes, &device);
    assert_eq!(config.coarse_tail, Some(true));
    // The same weights read as a fine tail (the header's flag dropped) decode other frames:
    // the flag is what the file's reader goes by.
    let (mut header, weights) = parts(&bytes);
    header["config"]
        .as_object_mut()
        .unwrap()
        .remove("coarse_tail");
    let (as_fine, _, config) = load_bytes(&assemble(&header, &weights), &device).unwrap();
    assert_eq!(config.coarse_tail, None);
    assert!(prediction_diff(&p, &as_fine.forward(&t).unwrap()) > 1e-4);
}

/// An attentive model that reads joints from frames: with a read-out that reads nothing yet
/// it predicts exactly as without one (`train --init --frame-joints` continues a file); once
/// it reads something, frames-only predictions start from what it reads while predictions
/// with joints observed stay as they were; it is saved and read back with its read-out; other
/// kinds refuse one.
#[test]
fn frame_joints_start_frames_only_predictions_from_the_joints_read() {
    let device = device();
    let plain = model(ModelKind::Attn, 64, &device);
    let reading = plain.clone().reading_frame_joints(&device).unwrap();
    assert_eq!(reading.config().frame_joints, Some(true));
    let b = batch(2, 3, 4, 64, 5);
    let predict = |m: &Model, blend: f32| {
        let mut b = b.clone();
        b.blend = vec![blend; 2];
        m.forward(&tensors(&b, &device).unwrap()).unwrap()
    };
    for blend in [1.0, 0.5, 0.0] {
        assert_eq!(
            prediction_diff(&predict(&plain, blend), &predict(&reading, blend)),
            0.0,
            "blend {blend}"
        );
    }
    let mut read = reading.clone();
    let dmbn::model::Network::Attn(net) = &mut read.network else {
        unreachable!()
    };
    let layer = net.frame_joints.as_mut().unwrap();
    let dims = layer.weight.dims();
    layer.weight = burn::module::Param::from_tensor(Tensor::random(
        dims,
        burn::tensor::Distribution::Uniform(-0.3, 0.3),
        &device,
    ));
    let frames_only = max_abs_diff(
        &predict(&reading, 1.0).joint_mean,
        &predict(&read, 1.0).joint_mean,
    );
    assert!(frames_only > 1e-2, "{frames_only}");
    for blend in [0.5, 0.0] {
        assert_eq!(
            prediction_diff(&predict(&reading, blend), &predict(&read, blend)),
            0.0,
            "blend {blend}"
        );
    }
    let bytes = save_bytes(&read, &Normalization::identity(JOINTS), false).unwrap();
    let (config, _) = reads_back_exactly(&read, &bytes, &device);
    assert_eq!(config.frame_joints, Some(true));
    // DMBN-PTE has no attention to start from what it reads.
    let pte = model(ModelKind::Pte, 64, &device);
    let err = pte.reading_frame_joints(&device).err().unwrap();
    assert!(err.to_string().contains("frame_joints"), "{err}");
    let err = ModelConfig::new(ModelKind::Pte)
        .with_frame_joints(Some(true))
        .init(&device)
        .err()
        .unwrap();
    assert!(err.to_string().contains("frame_joints"), "{err}");
}

/// A joint σ scale is written into the header, leaves the weights and every other output as
/// they are, multiplies the predicted joint σ exactly (its forecast factor outside the span
/// of the observed times, its other one within it), and must be a finite number above 0.
#[test]
fn a_joint_sigma_scale_multiplies_the_joint_sigma() {
    let device = device();
    let model = model(ModelKind::Pte, 64, &device);
    let norm = Normalization {
        mean: vec![0.1; 7],
        std: vec![0.5; 7],
    };
    let bytes = save_bytes(&model, &norm, false).unwrap();
    let scale = |between: f32, forecast: Option<f32>| JointSigmaScale { between, forecast };
    let scaled = with_joint_sigma_scale(&bytes, scale(1.75, Some(0.5))).unwrap();
    let header = read_header(&bytes).unwrap();
    assert_eq!(
        (header.joint_sigma_scale, header.forecast_joint_sigma_scale),
        (None, None)
    );
    let header = read_header(&scaled).unwrap();
    assert_eq!(
        (header.joint_sigma_scale, header.forecast_joint_sigma_scale),
        (Some(1.75), Some(0.5))
    );
    let seq = dmbn::sim::episode(dmbn::sim::Action::Grasp, 3, 64).unwrap();
    let observations = dmbn::predict::Observations::from_sequence(&seq, &[2, 20]).unwrap();
    // Before the first observation, between them (both ends included), after the last.
    let targets: Vec<usize> = vec![0, 1, 2, 10, 20, 21, 40];
    let times: Vec<f32> = targets.iter().map(|&k| seq.times()[k]).collect();
    let predict = |bytes: &[u8]| {
        dmbn::predict::Predictor::from_bytes(bytes)
            .unwrap()
            .predict(&observations, &times, 0.5)
            .unwrap()
    };
    let (plain, wide) = (predict(&bytes), predict(&scaled));
    assert_eq!(plain.joint_mean, wide.joint_mean);
    assert_eq!(plain.image_mean, wide.image_mean);
    assert_eq!(plain.image_sigma, wide.image_sigma);
    for (i, &k) in targets.iter().enumerate() {
        let factor = if (2..=20).contains(&k) { 1.75 } else { 0.5 };
        for j in 0..7 {
            let (a, b) = (plain.joint_sigma[i * 7 + j], wide.joint_sigma[i * 7 + j]);
            assert!(
                (b - factor * a).abs() <= 1e-6 * b.abs(),
                "step {k}: {a} {b}"
            );
        }
    }
    // Setting it again replaces it; without a forecast factor, one factor everywhere.
    let again = with_joint_sigma_scale(&scaled, scale(0.5, None)).unwrap();
    let header = read_header(&again).unwrap();
    assert_eq!(
        (header.joint_sigma_scale, header.forecast_joint_sigma_scale),
        (Some(0.5), None)
    );
    for (a, b) in plain.joint_sigma.iter().zip(&predict(&again).joint_sigma) {
        assert!((b - 0.5 * a).abs() <= 1e-6 * b.abs(), "{a} {b}");
    }
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let err = with_joint_sigma_scale(&bytes, scale(bad, None))
            .err()
            .unwrap();
        assert!(
            err.to_string().contains("joint_sigma_scale"),
            "{bad}: {err}"
        );
        let err = with_joint_sigma_scale(&bytes, scale(1.0, Some(bad)))
            .err()
            .unwrap();
        assert!(
            err.to_string().contains("forecast_joint_sigma_scale"),
            "{bad}: {err}"
        );
    }
    // A file whose header says so is refused, naming the field.
    for field in ["joint_sigma_scale", "forecast_joint_sigma_scale"] {
        let (mut header, weights) = parts(&scaled);
        header[field] = serde_json::json!(-2.0);
        let err = load_err(&assemble(&header, &weights));
        assert!(err.to_string().contains(field), "{err}");
    }
}

/// Rebuilds a file from a header and a weight section (the checksum and length follow the
/// weights unless the header says otherwise).
fn assemble(header: &serde_json::Value, weights: &[u8]) -> Vec<u8> {
    let header = serde_json::to_vec(header).unwrap();
    let mut out = file::MAGIC.to_vec();
    out.extend_from_slice(&file::FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&(weights.len() as u64).to_le_bytes());
    out.extend_from_slice(weights);
    out
}

/// The header (as JSON) and the weight section of a file.
fn parts(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let header_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let header = serde_json::from_slice(&bytes[16..16 + header_len]).unwrap();
    (header, bytes[24 + header_len..].to_vec())
}

fn load_err(bytes: &[u8]) -> ModelError {
    match load_bytes(bytes, &device()) {
        Ok(_) => panic!("a bad file loaded"),
        Err(e) => e,
    }
}

#[test]
fn bad_files_give_clear_errors() {
    let device = device();
    let (_, bytes, _) = saved(ModelKind::Dmbn, false);
    let header_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;

    // Truncated at every section.
    for (cut, what) in [
        (3, "the magic bytes"),
        (10, "the format version"),
        (14, "the header length"),
        (16 + header_len / 2, "the header"),
        (16 + header_len + 3, "the weights length"),
        (bytes.len() - 1, "the weights"),
    ] {
        match load_err(&bytes[..cut]) {
            ModelError::Truncated { what: w, .. } => assert_eq!(w, what, "cut at {cut}"),
            e => panic!("cut at {cut}: {e}"),
        }
    }
    assert!(load_err(&bytes[..bytes.len() - 1])
        .to_string()
        .contains("truncated"));

    // Not a model file: bad magic, random bytes, empty.
    let mut bad = bytes.clone();
    bad[0] = b'X';
    assert!(matches!(load_err(&bad), ModelError::NotAModelFile));
    let random = Lcg(9).fill(5000, 255.0, 0.0);
    let random: Vec<u8> = random.into_iter().map(|v| v as u8).collect();
    assert!(matches!(load_err(&random), ModelError::NotAModelFile));
    assert!(matches!(load_err(&[]), ModelError::NotAModelFile));

    // Unknown version.
    let mut bad = bytes.clone();
    bad[8..12].copy_from_slice(&2u32.to_le_bytes());
    let err = load_err(&bad);
    assert!(
        matches!(
            err,
            ModelError::Version {
                found: 2,
                supported: 1
            }
        ),
        "{err}"
    );

    // Bad header JSON.
    let mut bad = bytes.clone();
    bad[16] = b'#';
    assert!(matches!(load_err(&bad), ModelError::Header(_)));

    // Trailing bytes and corrupt weights.
    let mut bad = bytes.clone();
    bad.push(0);
    assert!(matches!(
        load_err(&bad),
        ModelError::TrailingBytes { found: 1 }
    ));
    let mut bad = bytes.clone();
    let last = bad.len() - 100;
    bad[last] ^= 0xff;
    assert!(matches!(load_err(&bad), ModelError::Checksum));

    // Other kind or size than asked for.
    let err = load_bytes_expecting(&bytes, &device, Some(ModelKind::Pte), None).unwrap_err();
    assert!(matches!(err, ModelError::Kind { .. }), "{err}");
    assert!(err.to_string().contains("dmbn") && err.to_string().contains("pte"));
    let err = load_bytes_expecting(&bytes, &device, None, Some(128)).unwrap_err();
    assert!(
        matches!(
            err,
            ModelError::FileImageSize {
                expected: 128,
                found: 64
            }
        ),
        "{err}"
    );
    assert!(load_bytes_expecting(&bytes, &device, Some(ModelKind::Dmbn), Some(64)).is_ok());

    // A header whose config does not describe the weights: other hidden size, other kind,
    // other image size.
    let (header, weights) = parts(&bytes);
    for (field, value) in [
        ("hidden", serde_json::json!(64)),
        ("kind", serde_json::json!("pte")),
        ("image_size", serde_json::json!(128)),
    ] {
        let mut header = header.clone();
        header["config"][field] = value;
        let err = load_err(&assemble(&header, &weights));
        assert!(matches!(err, ModelError::Weights(_)), "{field}: {err}");
    }
    // An invalid config or normalisation in the header.
    let mut bad_header = header.clone();
    bad_header["config"]["image_size"] = serde_json::json!(100);
    let err = load_err(&assemble(&bad_header, &weights));
    assert!(
        matches!(
            err,
            ModelError::Config {
                field: "image_size",
                ..
            }
        ),
        "{err}"
    );
    let mut bad_header = header.clone();
    bad_header["normalization"]["std"][3] = serde_json::json!(0.0);
    let err = load_err(&assemble(&bad_header, &weights));
    assert!(
        matches!(
            err,
            ModelError::Normalization {
                field: "std",
                index: 3,
                ..
            }
        ),
        "{err}"
    );
    let mut bad_header = header.clone();
    bad_header["config"]["kind"] = serde_json::json!("cnp");
    assert!(matches!(
        load_err(&assemble(&bad_header, &weights)),
        ModelError::Header(_)
    ));
    // The untouched parts reassemble into a good file.
    assert!(load_bytes(&assemble(&header, &weights), &device).is_ok());
}

fn batch_err(batch: &Batch) -> ModelError {
    match tensors(batch, &device()) {
        Ok(_) => panic!("a bad batch was accepted"),
        Err(e) => e,
    }
}

#[test]
fn bad_batches_give_clear_errors() {
    let good = batch(2, 3, 2, 64, 7);
    assert!(tensors(&good, &device()).is_ok());

    let mut bad = good.clone();
    bad.context_images.truncate(100);
    let err = batch_err(&bad);
    assert!(
        matches!(
            err,
            ModelError::Length {
                field: "context_images",
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string().contains("[B=2, N=3, 3, S=64, S=64]"),
        "{err}"
    );

    // Frames of another size than stated.
    let mut bad = good.clone();
    bad.image_size = 128;
    assert!(matches!(
        batch_err(&bad),
        ModelError::Length {
            field: "context_images",
            ..
        }
    ));
    let mut bad = good.clone();
    bad.target_joints.push(0.0);
    assert!(matches!(
        batch_err(&bad),
        ModelError::Length {
            field: "target_joints",
            ..
        }
    ));
    let mut bad = good.clone();
    bad.blend.pop();
    assert!(matches!(
        batch_err(&bad),
        ModelError::Length { field: "blend", .. }
    ));

    // A sequence with no context at all.
    let mut bad = good.clone();
    bad.context_mask[3..6].fill(0.0);
    let err = batch_err(&bad);
    assert!(
        matches!(err, ModelError::EmptyContext { sequence: 1 }),
        "{err}"
    );
    let mut bad = good.clone();
    bad.context_mask[2] = 0.5;
    assert!(matches!(
        batch_err(&bad),
        ModelError::MaskValue { index: 2, .. }
    ));

    // Blend outside [0, 1], non-finite values, zero sizes.
    for value in [-0.1, 1.5, f32::NAN] {
        let mut bad = good.clone();
        bad.blend[1] = value;
        let err = batch_err(&bad);
        assert!(
            matches!(
                err,
                ModelError::Blend { sequence: 1, .. }
                    | ModelError::NotFinite { field: "blend", .. }
            ),
            "{err}"
        );
    }
    let mut bad = good.clone();
    bad.context_times[4] = f32::INFINITY;
    assert!(matches!(
        batch_err(&bad),
        ModelError::NotFinite {
            field: "context_times",
            index: 4,
            ..
        }
    ));
    let mut bad = good.clone();
    bad.targets = 0;
    assert!(matches!(
        batch_err(&bad),
        ModelError::EmptyDimension { field: "targets" }
    ));
    assert!(matches!(
        batch_err(&Batch::default()),
        ModelError::EmptyDimension { field: "batch" }
    ));

    // Targets are optional (inference), but the loss needs them.
    let device = device();
    let mut inference = good.clone();
    inference.target_images.clear();
    inference.target_joints.clear();
    let t = tensors(&inference, &device).unwrap();
    let model = model(ModelKind::Pte, 64, &device);
    let p = model.forward(&t).unwrap();
    assert!(matches!(
        model.loss(&p, &t, 0.0),
        Err(ModelError::MissingTargets {
            field: "target_images"
        })
    ));

    // A batch of 128 px frames for a 64 px model, and target times of the wrong shape.
    let t128 = tensors(&batch(1, 1, 1, 128, 8), &device).unwrap();
    assert!(matches!(
        model.forward(&t128),
        Err(ModelError::ImageSize {
            expected: 64,
            found: 128
        })
    ));
    let r = model.encode(&t).unwrap();
    let times = Tensor::<2>::from_data(TensorData::new(vec![0.5f32; 3], [3, 1]), &device);
    assert!(matches!(
        model.decode(&r, times),
        Err(ModelError::TargetTimes {
            batch: 2,
            found: [3, 1]
        })
    ));
}
