//! Training on a GPU through burn's wgpu backend (the cargo feature `wgpu`), on whatever wgpu
//! adapter the machine has; CI gives it a software Vulkan driver (Debian's
//! `mesa-vulkan-drivers`, lavapipe: `bash .ci/gpu`). From the same weights and batches, a step
//! on wgpu gives the CPU's losses within a stated tolerance, twice (so the gradients and the
//! Adam update agree too), the loss falls when training on, and a batch split between two
//! wgpu devices (the one adapter twice: replicas on threads, their gradients summed) gives
//! one device's losses. Without an adapter the tests are reported as skipped. Native only.
#![cfg(all(feature = "wgpu", not(target_arch = "wasm32")))]

mod support;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use burn::tensor::{DeviceKind, Tensor};
use dmbn::model::{ModelConfig, ModelKind};
use dmbn::sim::Action;
use dmbn::train::{TrainConfig, TrainDevice, TrainDevices, Trainer};

/// Relative tolerance of a wgpu loss against the CPU's: f32 kernels summing in other orders.
const TOLERANCE: f32 = 2e-3;

/// True when wgpu finds an adapter (else the calling test is reported as skipped).
fn wgpu_adapter() -> bool {
    let found = catch_unwind(AssertUnwindSafe(|| {
        let device = burn::tensor::Device::wgpu(DeviceKind::DefaultDevice);
        let x = Tensor::<1>::ones([4], &device);
        x.sum().into_scalar::<f32>()
    }));
    if !matches!(found, Ok(v) if v == 4.0) {
        support::skip("no wgpu adapter (install a Vulkan driver, e.g. mesa-vulkan-drivers)");
        return false;
    }
    true
}

fn small(kind: ModelKind, steps: u64, init: &Path) -> TrainConfig {
    let mut c = TrainConfig::new(ModelConfig::new(kind), steps, 3);
    c.batch = 2;
    c.targets_per_sequence = 2;
    c.max_contexts = 3;
    c.val_batches = 1;
    c.val_every = steps;
    c.checkpoint_every = steps;
    c.quality_sequences = 0;
    c.val_fraction = 0.0;
    // The same starting weights on both devices (their random generators differ).
    c.init = Some(init.to_path_buf());
    c
}

#[test]
fn a_wgpu_step_gives_the_cpus_losses() {
    if !wgpu_adapter() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..2, &Action::ALL, 500);
    for (kind, file) in [(ModelKind::Dmbn, "dmbn-sim"), (ModelKind::Attn, "attn-sim")] {
        let init = support::asset(&format!("models/{file}.dmbn"));
        let config = small(kind, 2, &init);
        let run = |device: TrainDevice| {
            let out = tmp.path().join(format!("{file}-{device}"));
            let mut trainer = Trainer::new_on(&device.into(), &data, &out, config.clone()).unwrap();
            [trainer.step().unwrap().0, trainer.step().unwrap().0]
        };
        let (cpu, gpu) = (run(TrainDevice::Cpu), run(TrainDevice::Wgpu(None)));
        for (step, (c, g)) in cpu.iter().zip(&gpu).enumerate() {
            for (what, c, g) in [
                ("loss", c.total, g.total),
                ("image NLL", c.image_nll, g.image_nll),
                ("joint NLL", c.joint_nll, g.joint_nll),
                ("image MSE", c.image_mse, g.image_mse),
                ("joint MSE", c.joint_mse, g.joint_mse),
            ] {
                println!("{file} step {step} {what}: cpu {c}, wgpu {g}");
                assert!(
                    (c - g).abs() <= TOLERANCE * c.abs().max(1.0),
                    "{file} step {step} {what}: cpu {c}, wgpu {g}"
                );
            }
        }
    }
}

#[test]
fn the_loss_falls_when_training_on_wgpu() {
    if !wgpu_adapter() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..1, &Action::ALL, 500);
    // Fresh weights, drawn on the GPU.
    let mut config = small(ModelKind::Pte, 30, Path::new(""));
    config.init = None;
    config.lr = 3e-4;
    let out = tmp.path().join("out");
    let mut trainer =
        Trainer::new_on(&TrainDevice::Wgpu(None).into(), &data, &out, config).unwrap();
    let losses: Vec<f32> = (0..30).map(|_| trainer.step().unwrap().0.total).collect();
    let mean = |s: &[f32]| s.iter().sum::<f32>() / s.len() as f32;
    let (first, last) = (mean(&losses[..5]), mean(&losses[25..]));
    println!("wgpu losses: {losses:?}");
    assert!(last < first - 0.05, "loss {first} -> {last}");
}

#[test]
fn a_batch_split_between_two_wgpu_devices_gives_one_device_s_losses() {
    if !wgpu_adapter() {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..2, &Action::ALL, 500);
    let config = small(ModelKind::Pte, 2, &support::asset("models/pte-sim.dmbn"));
    let run = |devices: &str| {
        let out = tmp.path().join(devices);
        let devices: TrainDevices = devices.parse().unwrap();
        let mut trainer = Trainer::new_on(&devices, &data, &out, config.clone()).unwrap();
        [trainer.step().unwrap().0, trainer.step().unwrap().0]
    };
    let (one, two) = (run("wgpu"), run("wgpu,wgpu"));
    for (step, (a, b)) in one.iter().zip(&two).enumerate() {
        println!("step {step}: one device {}, two {}", a.total, b.total);
        assert!(
            (a.total - b.total).abs() <= TOLERANCE * a.total.abs().max(1.0),
            "step {step}: one device {}, two {}",
            a.total,
            b.total
        );
    }
}
