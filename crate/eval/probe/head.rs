//! The probe's regression head and its fitting.
use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use rand::seq::index;
use rand::SeedableRng;
use rand_pcg::Pcg64;

use super::encodings::StepEncodings;
use crate::eval::standardizer::Standardizer;
use crate::model::values;

/// The probe's regression head and how it is fitted.
#[derive(Config, Debug)]
pub struct HeadConfig {
    /// Hidden units of the one-hidden-layer head.
    #[config(default = 64)]
    pub hidden: usize,
    /// Adam steps.
    #[config(default = 1500)]
    pub steps: usize,
    /// Encodings per step.
    #[config(default = 256)]
    pub batch: usize,
    /// Adam learning rate.
    #[config(default = 1e-3)]
    pub lr: f64,
}

/// A small fully connected head: encoding → ReLU hidden layer → time.
#[derive(Module, Debug)]
struct Head {
    hidden: Linear,
    out: Linear,
}

impl Head {
    fn forward(&self, x: Tensor<2>) -> Tensor<2> {
        self.out.forward(relu(self.hidden.forward(x)))
    }
}

/// Fits a head that regresses the time from `train` encodings (features standardised with the
/// training statistics, robustly: see [`crate::eval::REL_STD_FLOOR`] and [`crate::eval::STANDARD_CLIP`])
/// and returns its mean squared error on `test`. `image` picks the image or the joint
/// encodings. Deterministic for a seed while no other thread draws weights (burn's generator
/// is shared by every thread); NaN when either set is empty or the widths differ.
pub fn fit_head(
    train: &StepEncodings,
    test: &StepEncodings,
    image: bool,
    config: &HeadConfig,
    seed: u64,
) -> f64 {
    let pick = |e: &StepEncodings| {
        if image {
            e.image.clone()
        } else {
            e.joint.clone()
        }
    };
    let h = train.hidden;
    let (mut x_train, mut x_test) = (pick(train), pick(test));
    let (n, k) = (train.times.len(), test.times.len());
    if h == 0
        || n == 0
        || k == 0
        || test.hidden != h
        || x_train.len() != n * h
        || x_test.len() != k * h
        || config.hidden == 0
    {
        return f64::NAN;
    }
    // Standardise: the encoders' scales differ by orders of magnitude between models.
    let standardizer = Standardizer::fit(&x_train, h);
    standardizer.apply(&mut x_train, false);
    standardizer.apply(&mut x_test, true);
    let device = Device::flex().autodiff();
    device.seed(seed);
    let mut head = Head {
        hidden: LinearConfig::new(h, config.hidden).init(&device),
        out: LinearConfig::new(config.hidden, 1).init(&device),
    };
    let mut optim = AdamConfig::new().init();
    let mut rng = Pcg64::seed_from_u64(seed);
    let batch = config.batch.clamp(1, n);
    for _ in 0..config.steps {
        let rows = index::sample(&mut rng, train.times.len(), batch).into_vec();
        let x: Vec<f32> = rows
            .iter()
            .flat_map(|&r| x_train[r * h..(r + 1) * h].to_vec())
            .collect();
        let t: Vec<f32> = rows.iter().map(|&r| train.times[r]).collect();
        let x = Tensor::<2>::from_data(TensorData::new(x, [batch, h]), &device);
        let t = Tensor::<2>::from_data(TensorData::new(t, [batch, 1]), &device);
        let loss = (head.forward(x) - t).square().mean();
        let grads = GradientsParams::from_grads(loss.backward(), &head);
        head = optim.step(config.lr, head, grads);
    }
    let head = head.valid();
    let plain = Device::flex();
    let x = Tensor::<2>::from_data(TensorData::new(x_test, [k, h]), &plain);
    let t = Tensor::<2>::from_data(TensorData::new(test.times.clone(), [k, 1]), &plain);
    values((head.forward(x) - t).square().mean())
        .first()
        .map_or(f64::NAN, |&v| v as f64)
}
