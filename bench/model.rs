//! `cargo bench --bench model [-- --image-size 128]`: DMBN, DMBN-PTE and the attentive model on
//! the CPU (burn flex), 64×64 frames (or 128×128, the original data's: what the larger input costs).
//! Medians over repetitions of: one training step (8 sequences × 5 contexts × 4 targets:
//! forward, backward, Adam), inference of one target from 5 contexts, and of a 100-step
//! sequence from 5 contexts (encode once, decode in chunks). `bench/model.sh` runs this next
//! to the PyTorch script and the wasm (node) benchmark and prints the ratios.
use std::hint::black_box;
use std::time::Instant;

use burn::optim::grad_clipping::GradientClippingConfig;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::Device;
use rand::SeedableRng;
use rand_pcg::Pcg64;

use dmbn::augment::{Sampler, SamplerConfig};
use dmbn::data::{image_sizes_text, Normalization, IMAGE_SIZES, JOINTS};
use dmbn::model::{tensors, ModelConfig, ModelKind};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{self, Action};

const REPEATS: usize = 10;

fn median_ms(repeats: usize, mut f: impl FnMut()) -> f64 {
    f();
    f();
    let mut v: Vec<f64> = (0..repeats)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn main() {
    // `cargo test --benches` runs this too: keep that cheap.
    if std::env::args().any(|a| a == "--test" || a == "--list") {
        return;
    }
    let size = match image_size() {
        Ok(size) => size,
        Err(message) => {
            eprintln!("error: {message}");
            std::process::exit(2);
        }
    };
    let pool: Vec<_> = (0..4)
        .flat_map(|seed| {
            Action::ALL
                .into_iter()
                .map(move |a| sim::episode(a, seed, size as u32).expect("simulator"))
        })
        .collect();
    let norm = Normalization::fit(JOINTS, pool.iter().flat_map(|s| s.joints.rows()));
    let sampler = Sampler::new(SamplerConfig {
        batch: 8,
        max_contexts: 5,
        targets: 4,
        contexts_in_targets: false,
        joint_targets: 0,
        single_modality: 0.0,
        prefix_contexts: 0.0,
        warp: None,
    });
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "model benchmark: burn flex, {size}x{size}, median of {REPEATS} runs, {threads} threads available"
    );
    let mut json = Vec::new();
    for kind in ModelKind::ALL {
        let device = Device::flex().autodiff();
        device.seed(0);
        let config = ModelConfig::new(kind).with_image_size(size);
        let mut model = config.init(&device).expect("valid config");
        let mut optim = AdamConfig::new()
            .with_grad_clipping(Some(GradientClippingConfig::Norm(1.0)))
            .init();
        let mut rng = Pcg64::seed_from_u64(0);
        let mut batch = sampler.sample(&pool, &norm, &mut rng);
        // Five contexts in every sequence, as the benchmark's shapes say.
        batch.context_mask.fill(1.0);
        let batch = tensors(&batch, &device).expect("valid batch");
        let train = median_ms(REPEATS, || {
            let prediction = model.forward(&batch).expect("forward");
            let loss = model.loss(&prediction, &batch, 0.0).expect("loss");
            let grads = GradientsParams::from_grads(loss.total.backward(), &model);
            model = optim.step(1e-4, model.clone(), grads);
        });

        let device = Device::flex();
        let fresh = config.init(&device).expect("valid config");
        let predictor = Predictor::new(fresh, norm.clone());
        let seq = &pool[0];
        let observations = Observations::from_sequence(seq, &[0, 10, 20, 30, 40]).expect("steps");
        let one = median_ms(REPEATS * 5, || {
            black_box(
                predictor
                    .predict(&observations, &[0.5], 0.5)
                    .expect("predict"),
            );
        });
        let times: Vec<f32> = (0..100).map(|k| k as f32 / 99.0).collect();
        let sequence = median_ms(REPEATS, || {
            black_box(
                predictor
                    .predict(&observations, &times, 0.5)
                    .expect("predict"),
            );
        });
        println!(
            "{kind:>5}: train step {train:8.1} ms   infer 1 target {one:7.2} ms   infer 100 steps {sequence:8.1} ms"
        );
        json.push(format!(
            "{{\"model\":\"{kind}\",\"image_size\":{size},\"train_step_ms\":{train:.2},\"infer_one_ms\":{one:.3},\"infer_sequence100_ms\":{sequence:.2}}}"
        ));
    }
    println!("json: [{}]", json.join(","));
}

/// The frame size from `--image-size N` (default 64): one the networks are defined for.
fn image_size() -> Result<usize, String> {
    let args: Vec<String> = std::env::args().collect();
    let Some(i) = args.iter().position(|a| a == "--image-size") else {
        return Ok(64);
    };
    let value = args.get(i + 1).map(String::as_str).unwrap_or("");
    match value.parse::<usize>() {
        Ok(size) if IMAGE_SIZES.contains(&size) => Ok(size),
        _ => Err(format!(
            "--image-size is {value:?}: expected {}",
            image_sizes_text()
        )),
    }
}
