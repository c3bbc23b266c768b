use burn::tensor::{Device, Tensor, TensorData};

/// The weights of the linear interpolation of observations at `target` time: between the
/// nearest real observations before and after it, held before the first and after the last;
/// an observation at the target's own time gets all the weight. `times` and `real` describe
/// the observations in any order (`real[i]` false for a padding slot, which gets 0); with no
/// real observation every weight is 0.
///
/// The trivial baseline of the quality benchmark, and where the attentive model's decoders
/// start: a CNP that only learns a correction of it goes through its observations.
pub fn linear_weights(times: &[f32], real: &[bool], target: f32) -> Vec<f32> {
    let mut weights = vec![0.0; times.len()];
    let real_times = || (0..times.len()).filter(|&i| real[i]);
    let before = real_times()
        .filter(|&i| times[i] <= target)
        .max_by(|&a, &b| times[a].total_cmp(&times[b]));
    let after = real_times()
        .filter(|&i| times[i] >= target)
        .min_by(|&a, &b| times[a].total_cmp(&times[b]));
    match (before, after) {
        (Some(a), Some(b)) if times[b] > times[a] => {
            let w = (target - times[a]) / (times[b] - times[a]);
            weights[a] = 1.0 - w;
            weights[b] = w;
        }
        (Some(i), _) | (None, Some(i)) => weights[i] = 1.0,
        (None, None) => {}
    }
    weights
}

/// How far `target` is from the nearest real observation at or before it and at or after
/// it: where it sits in the gap it falls in, and how long that gap is (past the last
/// observation: how far ahead it forecasts). Infinite on a side with no observation.
pub fn gaps(times: &[f32], real: &[bool], target: f32) -> [f32; 2] {
    let side = |before: bool| {
        (0..times.len())
            .filter(|&i| {
                real[i]
                    && if before {
                        times[i] <= target
                    } else {
                        times[i] >= target
                    }
            })
            .map(|i| (times[i] - target).abs())
            .fold(f32::INFINITY, f32::min)
    };
    [side(true), side(false)]
}

/// [`linear_weights`] and [`gaps`] for a batch: `[B, M]` target times, `[B, N]` context
/// times and mask (1 real, 0 padding) to `[B, M, N]` weights and `[B, M, 2]` gaps (infinite
/// ones as 1, the length of a whole action).
/// Both depend on the times alone, so they are computed as plain numbers and carry no
/// gradient.
pub fn interpolation_tensors(
    target_times: &Tensor<2>,
    context_times: &Tensor<2>,
    context_mask: &Tensor<2>,
    device: &Device,
) -> (Tensor<3>, Tensor<3>) {
    let [b, m] = target_times.dims();
    let n = context_times.dims()[1];
    let read = |t: &Tensor<2>| -> Vec<f32> {
        t.to_data()
            .convert::<f32>()
            .try_to_vec()
            .expect("f32 after convert")
    };
    let (targets, times, mask) = (read(target_times), read(context_times), read(context_mask));
    let mut weights = Vec::with_capacity(b * m * n);
    let mut distances = Vec::with_capacity(b * m * 2);
    for s in 0..b {
        let times = &times[s * n..(s + 1) * n];
        let real: Vec<bool> = mask[s * n..(s + 1) * n].iter().map(|&v| v > 0.5).collect();
        for &t in &targets[s * m..(s + 1) * m] {
            weights.extend(linear_weights(times, &real, t));
            distances.extend(gaps(times, &real, t).map(|d| d.min(1.0)));
        }
    }
    (
        Tensor::from_data(TensorData::new(weights, [b, m, n]), device),
        Tensor::from_data(TensorData::new(distances, [b, m, 2]), device),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_between_neighbours_and_holds_outside() {
        // Unordered, with a padding slot nearer than any real one.
        let times = [0.5, 0.1, 0.3, 0.31];
        let real = [true, true, true, false];
        let close = |got: Vec<f32>, want: [f32; 4]| {
            assert!(
                got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6),
                "{got:?}"
            );
        };
        close(linear_weights(&times, &real, 0.2), [0.0, 0.5, 0.5, 0.0]);
        close(linear_weights(&times, &real, 0.35), [0.25, 0.0, 0.75, 0.0]);
        close(linear_weights(&times, &real, 0.3), [0.0, 0.0, 1.0, 0.0]);
        close(linear_weights(&times, &real, 0.0), [0.0, 1.0, 0.0, 0.0]);
        close(linear_weights(&times, &real, 0.9), [1.0, 0.0, 0.0, 0.0]);
        close(linear_weights(&times, &[false; 4], 0.9), [0.0; 4]);
        // The padding slot at 0.31 is not the nearest observation of 0.32: 0.3 is.
        let [before, after] = gaps(&times, &real, 0.32);
        assert!((before.min(after) - 0.02).abs() < 1e-6);
        assert_eq!(gaps(&times, &[false; 4], 0.9), [f32::INFINITY; 2]);
        let close2 = |[a, b]: [f32; 2], [c, d]: [f32; 2]| {
            assert!((a - c).abs() < 1e-6 && (b - d).abs() < 1e-6, "{a} {b}")
        };
        close2(gaps(&times, &real, 0.2), [0.1, 0.1]);
        close2(gaps(&times, &real, 0.3), [0.0, 0.0]);
        close2(gaps(&times, &real, 0.45), [0.15, 0.05]);
        let [before, after] = gaps(&times, &real, 0.9);
        assert!((before - 0.4).abs() < 1e-6 && after == f32::INFINITY);
    }

    #[test]
    fn the_batch_tensor_holds_each_sequence_s_weights() {
        let device = Device::flex();
        let targets = Tensor::<2>::from_floats([[0.25], [0.9]], &device);
        let times = Tensor::<2>::from_floats([[0.0, 0.5], [0.2, 0.4]], &device);
        let mask = Tensor::<2>::from_floats([[1.0, 1.0], [1.0, 0.0]], &device);
        let (w, d) = interpolation_tensors(&targets, &times, &mask, &device);
        let w: Vec<f32> = w.into_data().try_to_vec().unwrap();
        assert_eq!(w, vec![0.5, 0.5, 1.0, 0.0]);
        let d: Vec<f32> = d.into_data().try_to_vec().unwrap();
        // Before and after each target; nothing after 0.9 (capped at 1).
        let want = [0.25, 0.25, 0.7, 1.0];
        assert!(
            d.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6),
            "{d:?}"
        );
    }
}
