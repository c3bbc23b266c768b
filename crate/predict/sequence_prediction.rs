use super::heat_map;
use crate::data::{Normalization, JOINTS};

/// The predicted Gaussian at T target times, in dataset units: frames as interleaved RGB in
/// [0, 1] (rows top to bottom, like [`crate::data::Sequence::frames`]), joints in radians
/// (and gripper units), σ alongside each.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SequencePrediction {
    /// S: frame width and height.
    pub image_size: usize,
    /// `T`: the target times.
    pub times: Vec<f32>,
    /// `T × S × S × 3`: mean frames.
    pub image_mean: Vec<f32>,
    /// `T × S × S × 3`: σ of every pixel channel.
    pub image_sigma: Vec<f32>,
    /// `T × 7`: mean joints.
    pub joint_mean: Vec<f32>,
    /// `T × 7`: σ of every joint.
    pub joint_sigma: Vec<f32>,
}

impl SequencePrediction {
    /// No targets yet.
    pub fn empty(image_size: usize) -> Self {
        SequencePrediction {
            image_size,
            ..Default::default()
        }
    }

    /// T: predicted steps.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True when nothing was predicted.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    fn frame_len(&self) -> usize {
        self.image_size * self.image_size * 3
    }

    /// Mean frame `k` as RGB bytes.
    pub fn mean_frame(&self, k: usize) -> Vec<u8> {
        let n = self.frame_len();
        self.image_mean[k * n..(k + 1) * n]
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect()
    }

    /// σ of frame `k`, `S × S × 3`.
    pub fn sigma_frame(&self, k: usize) -> &[f32] {
        let n = self.frame_len();
        &self.image_sigma[k * n..(k + 1) * n]
    }

    /// The largest pixel σ of the whole prediction: the common scale of its heat maps.
    pub fn max_image_sigma(&self) -> f32 {
        self.image_sigma.iter().copied().fold(0.0, f32::max)
    }

    /// σ of frame `k` as an RGB heat map scaled so that `scale` is full yellow.
    pub fn sigma_map(&self, k: usize, scale: f32) -> Vec<u8> {
        heat_map(self.sigma_frame(k), scale)
    }

    /// Appends the model's outputs for `times` (channels-first frames, normalised joints),
    /// converting them to dataset units.
    pub(crate) fn push(
        &mut self,
        times: &[f32],
        image_mean: &[f32],
        image_sigma: &[f32],
        joint_mean: &[f32],
        joint_sigma: &[f32],
        normalization: &Normalization,
    ) {
        let s = self.image_size;
        let plane = s * s;
        self.times.extend_from_slice(times);
        for (source, out) in [
            (image_mean, &mut self.image_mean),
            (image_sigma, &mut self.image_sigma),
        ] {
            for frame in source.chunks_exact(3 * plane) {
                out.extend((0..plane).flat_map(|p| (0..3).map(move |c| frame[c * plane + p])));
            }
        }
        for (mean, sigma) in joint_mean
            .chunks_exact(JOINTS)
            .zip(joint_sigma.chunks_exact(JOINTS))
        {
            let mean: [f32; JOINTS] = std::array::from_fn(|j| mean[j]);
            self.joint_mean.extend(normalization.denormalize(&mean));
            self.joint_sigma
                .extend(sigma.iter().zip(normalization.std).map(|(s, std)| s * std));
        }
    }
}
