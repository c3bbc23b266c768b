/// The colour of a value in [0, 1] (clamped; NaN counts as 0) on a perceptually ordered
/// black → purple → orange → yellow scale (an "inferno"-like ramp), as RGB bytes.
pub fn heat_map_rgb(value: f32) -> [u8; 3] {
    // Stops of matplotlib's inferno at 0, 0.25, 0.5, 0.75, 1.
    const STOPS: [[f32; 3]; 5] = [
        [0.0, 0.0, 4.0],
        [87.0, 16.0, 110.0],
        [188.0, 55.0, 84.0],
        [249.0, 142.0, 9.0],
        [252.0, 255.0, 164.0],
    ];
    let v = if value.is_nan() {
        0.0
    } else {
        value.clamp(0.0, 1.0)
    } * 4.0;
    let i = (v.floor() as usize).min(3);
    let f = v - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    std::array::from_fn(|c| (a[c] + (b[c] - a[c]) * f).round() as u8)
}

/// The σ of each pixel of `sigma` (σ per channel, RGB interleaved: `… × 3`): the mean of its
/// three channels, the σ that the heat maps show.
pub fn pixel_sigma(sigma: &[f32]) -> Vec<f32> {
    sigma
        .chunks_exact(3)
        .map(|px| (px[0] + px[1] + px[2]) / 3.0)
        .collect()
}

/// Pixel σ (`S × S`, see [`pixel_sigma`]) as an RGB heat map (`S × S × 3` bytes), divided by
/// `scale` (the σ shown as full yellow: the largest σ of a prediction,
/// [`SequencePrediction::max_image_sigma`](super::SequencePrediction::max_image_sigma), to
/// compare its frames; a scale that is not positive and finite counts as 1).
pub fn heat_map(pixel_sigma: &[f32], scale: f32) -> Vec<u8> {
    let scale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        1.0
    };
    pixel_sigma
        .iter()
        .flat_map(|&s| heat_map_rgb(s / scale))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_order() {
        assert_eq!(heat_map_rgb(0.0), [0, 0, 4]);
        assert_eq!(heat_map_rgb(1.0), [252, 255, 164]);
        assert_eq!(heat_map_rgb(2.0), heat_map_rgb(1.0));
        assert_eq!(heat_map_rgb(f32::NAN), heat_map_rgb(0.0));
        let brightness = |v| heat_map_rgb(v).iter().map(|&c| c as u32).sum::<u32>();
        assert!(brightness(0.2) < brightness(0.5) && brightness(0.5) < brightness(0.9));
        assert_eq!(heat_map(&[0.5; 2], 0.5), vec![252, 255, 164, 252, 255, 164]);
        assert_eq!(heat_map(&[0.5], 0.0), heat_map(&[0.5], 1.0));
        assert_eq!(
            pixel_sigma(&[0.25, 0.5, 0.75, 0.125, 0.125, 0.125]),
            vec![0.5, 0.125]
        );
    }
}
