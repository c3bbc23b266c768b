use super::{heat_map, pixel_sigma};
use crate::data::Normalization;

/// The predicted Gaussian at T target times, in dataset units: frames as interleaved RGB in
/// [0, 1] (rows top to bottom, like [`crate::data::Sequence::frames`]), joints in radians
/// (and gripper units), σ alongside each.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SequencePrediction {
    /// S: frame width and height.
    pub image_size: usize,
    /// D: joint values a step.
    pub joints: usize,
    /// `T`: the target times.
    pub times: Vec<f32>,
    /// `T × S × S × 3`: mean frames.
    pub image_mean: Vec<f32>,
    /// `T × S × S × 3`: σ of every pixel channel.
    pub image_sigma: Vec<f32>,
    /// `T × D`: mean joints.
    pub joint_mean: Vec<f32>,
    /// `T × D`: σ of every joint.
    pub joint_sigma: Vec<f32>,
}

impl SequencePrediction {
    /// No targets yet, for frames of `image_size` pixels a side and `joints` values a step.
    pub fn empty(image_size: usize, joints: usize) -> Self {
        SequencePrediction {
            image_size,
            joints,
            ..Default::default()
        }
    }

    /// The mean joints of step `k`.
    pub fn joint_mean_at(&self, k: usize) -> &[f32] {
        &self.joint_mean[k * self.joints..(k + 1) * self.joints]
    }

    /// The joint σ of step `k`.
    pub fn joint_sigma_at(&self, k: usize) -> &[f32] {
        &self.joint_sigma[k * self.joints..(k + 1) * self.joints]
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
        rgb_bytes(&self.image_mean[k * n..(k + 1) * n])
    }

    /// Every mean frame as RGB bytes, `T × S × S × 3`.
    pub fn mean_frames(&self) -> Vec<u8> {
        rgb_bytes(&self.image_mean)
    }

    /// σ of frame `k`, `S × S × 3`.
    pub fn sigma_frame(&self, k: usize) -> &[f32] {
        let n = self.frame_len();
        &self.image_sigma[k * n..(k + 1) * n]
    }

    /// σ of every pixel, `T × S × S`: the mean of its channels ([`pixel_sigma`]), what the
    /// heat maps show.
    pub fn pixel_sigma(&self) -> Vec<f32> {
        pixel_sigma(&self.image_sigma)
    }

    /// The largest pixel σ of the whole prediction (see [`Self::pixel_sigma`]; 0 when empty):
    /// the common scale of its heat maps, the σ shown as full yellow by `dmbn predict`, the
    /// evaluation figure and the page (which takes the largest over its decoded chunks).
    pub fn max_image_sigma(&self) -> f32 {
        // A comparison, not f32::max (in wasm a call of libm's fmaxf per pixel); NaN is passed
        // over as f32::max does.
        pixel_sigma(&self.image_sigma)
            .into_iter()
            .fold(0.0, |m, s| if s > m { s } else { m })
    }

    /// σ of frame `k` as an RGB heat map scaled so that `scale` is full yellow.
    pub fn sigma_map(&self, k: usize, scale: f32) -> Vec<u8> {
        heat_map(&pixel_sigma(self.sigma_frame(k)), scale)
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
            // Channels-first to channels-last, into room made first (an indexed loop: an
            // iterator-fed extend costs as much as the heads that computed the values).
            let first = out.len();
            out.resize(first + source.len(), 0.0);
            let frames = source.chunks_exact(3 * plane);
            for (frame, dst) in frames.zip(out[first..].chunks_exact_mut(3 * plane)) {
                for (c, channel) in frame.chunks_exact(plane).enumerate() {
                    for (p, &v) in channel.iter().enumerate() {
                        dst[3 * p + c] = v;
                    }
                }
            }
        }
        let d = self.joints;
        for (mean, sigma) in joint_mean.chunks_exact(d).zip(joint_sigma.chunks_exact(d)) {
            self.joint_mean.extend(normalization.denormalize(mean));
            self.joint_sigma
                .extend(sigma.iter().zip(&normalization.std).map(|(s, std)| s * std));
        }
    }
}

/// Values in [0, 1] (clamped) as bytes, rounded half away from zero.
fn rgb_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().map(|&v| byte(v)).collect()
}

/// `(v.clamp(0.0, 1.0) * 255.0).round() as u8` without `f32::round`, which wasm has no
/// instruction for (each byte a call of libm's `roundf`): NaN and below 0 saturate to 0,
/// above 1 to 255.
#[inline(always)]
fn byte(v: f32) -> u8 {
    let x = v * 255.0;
    let whole = x.trunc();
    (if x - whole >= 0.5 { whole + 1.0 } else { whole }) as u8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;
    use crate::predict::heat_map_rgb;

    #[test]
    fn the_largest_sigma_is_the_brightest_pixel_of_the_heat_map() {
        let p = SequencePrediction {
            image_size: 1,
            times: vec![0.0, 1.0],
            image_mean: vec![0.0, 0.5, 2.0, 1.0, -1.0, 0.25],
            image_sigma: vec![0.25, 0.5, 0.75, 0.125, 0.125, 0.125],
            ..SequencePrediction::empty(1, JOINTS)
        };
        assert_eq!(p.pixel_sigma(), vec![0.5, 0.125]);
        // The mean of the channels, not the largest channel (0.75).
        assert_eq!(p.max_image_sigma(), 0.5);
        assert_eq!(p.sigma_map(0, p.max_image_sigma()), heat_map_rgb(1.0));
        assert_eq!(p.sigma_map(1, p.max_image_sigma()), heat_map_rgb(0.25));
        assert_eq!(p.mean_frames(), vec![0, 128, 255, 255, 0, 64]);
        assert_eq!(p.mean_frames()[3..], p.mean_frame(1));
        assert_eq!(SequencePrediction::empty(4, JOINTS).max_image_sigma(), 0.0);
    }

    #[test]
    fn bytes_round_as_f32_round_does() {
        for i in -1000..=300_000 {
            let v = i as f32 / 256_000.0;
            assert_eq!(byte(v), (v.clamp(0.0, 1.0) * 255.0).round() as u8, "{v}");
        }
        for v in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.5 / 255.0,
            1.5 / 255.0,
        ] {
            assert_eq!(byte(v), (v.clamp(0.0, 1.0) * 255.0).round() as u8, "{v}");
        }
    }
}
