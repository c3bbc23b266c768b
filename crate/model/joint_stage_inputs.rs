//! What the joint stage ([`super::JointStage`]) sees of a target time: the glimpses side by
//! side and where the linear interpolation of their reads puts the joints there. Plain arrays,
//! built the same way for training and for inference, natively and in wasm.
use crate::data::Joints;

/// Glimpses the stage sees at once: with more, each target sees the nearest in time.
pub const JOINT_STAGE_SLOTS: usize = 8;
/// Frequencies of the target phase's sine and cosine features (π·f·phase, f = 1…8).
pub const JOINT_STAGE_FREQUENCIES: usize = 8;

/// Values per slot for `d` joint values: the read joints, the glimpse's time less the
/// target's, 1 (the slot is filled).
fn slot_len(d: usize) -> usize {
    d + 2
}

/// Input features per target for `d` joint values: the slots, the interpolated reads, the
/// phase and its sines and cosines.
pub fn joint_stage_input_len(d: usize) -> usize {
    JOINT_STAGE_SLOTS * slot_len(d) + d + 1 + 2 * JOINT_STAGE_FREQUENCIES
}

/// The stage's inputs at `targets` (phases) for glimpses at `times` whose joints were read as
/// `reads` (one row per glimpse, in joint units; any order, at least one):
/// [`joint_stage_input_len`] features per target, and the reads linearly interpolated there
/// (D per target; held constant beyond the first and the last glimpse), which the stage
/// corrects.
pub fn joint_stage_inputs(times: &[f32], reads: &Joints, targets: &[f32]) -> (Vec<f32>, Vec<f32>) {
    assert_eq!(times.len(), reads.len(), "one read per glimpse");
    assert!(!times.is_empty(), "at least one glimpse");
    let d = reads.width();
    let slot = slot_len(d);
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let mut x = Vec::with_capacity(targets.len() * joint_stage_input_len(d));
    let mut start = Vec::with_capacity(targets.len() * d);
    for &phase in targets {
        let interpolated = interpolate(&order, times, reads, phase);
        for &i in &slots(&order, times, phase) {
            x.extend_from_slice(&reads[i]);
            x.extend([times[i] - phase, 1.0]);
        }
        x.resize(
            x.len() + (JOINT_STAGE_SLOTS - order.len().min(JOINT_STAGE_SLOTS)) * slot,
            0.0,
        );
        x.extend_from_slice(&interpolated);
        x.push(phase);
        let angle = |f: usize| std::f32::consts::PI * phase * f as f32;
        x.extend((1..=JOINT_STAGE_FREQUENCIES).map(|f| angle(f).sin()));
        x.extend((1..=JOINT_STAGE_FREQUENCIES).map(|f| angle(f).cos()));
        start.extend_from_slice(&interpolated);
    }
    (x, start)
}

/// The glimpses a target at `phase` sees, in time order: all of them, or the
/// [`JOINT_STAGE_SLOTS`] nearest in time when there are more.
fn slots(order: &[usize], times: &[f32], phase: f32) -> Vec<usize> {
    if order.len() <= JOINT_STAGE_SLOTS {
        return order.to_vec();
    }
    let mut near = order.to_vec();
    near.sort_by(|&a, &b| {
        (times[a] - phase)
            .abs()
            .total_cmp(&(times[b] - phase).abs())
    });
    near.truncate(JOINT_STAGE_SLOTS);
    near.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    near
}

/// `values` (one row per glimpse at `times`, any order) linearly interpolated at each of
/// `targets`, held constant beyond the first and the last glimpse.
pub(super) fn interpolated(times: &[f32], values: &Joints, targets: &[f32]) -> Vec<Vec<f32>> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    (targets.iter())
        .map(|&phase| interpolate(&order, times, values, phase))
        .collect()
}

/// The reads linearly interpolated at `phase` (`order`: the glimpses in time order).
fn interpolate(order: &[usize], times: &[f32], reads: &Joints, phase: f32) -> Vec<f32> {
    let (first, last) = (order[0], order[order.len() - 1]);
    if phase <= times[first] {
        return reads[first].to_vec();
    }
    if phase >= times[last] {
        return reads[last].to_vec();
    }
    let after = order.partition_point(|&i| times[i] <= phase);
    let (a, b) = (order[after - 1], order[after]);
    let w = (phase - times[a]) / (times[b] - times[a]);
    reads[a]
        .iter()
        .zip(&reads[b])
        .map(|(ra, rb)| ra + w * (rb - ra))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const JOINTS: usize = crate::data::JOINTS;
    const SLOT: usize = JOINTS + 2;
    const JOINT_STAGE_INPUTS: usize =
        JOINT_STAGE_SLOTS * SLOT + JOINTS + 1 + 2 * JOINT_STAGE_FREQUENCIES;

    fn read(v: f32) -> [f32; JOINTS] {
        std::array::from_fn(|j| v + j as f32)
    }

    fn reads(rows: &[[f32; JOINTS]]) -> Joints {
        Joints::from_rows(rows)
    }

    #[test]
    fn interpolates_between_glimpses_in_any_order_and_holds_beyond_them() {
        let (x, start) = joint_stage_inputs(
            &[1.0, 0.0, 0.5],
            &reads(&[read(4.0), read(0.0), read(2.0)]),
            &[0.25, 0.75, 1.0, -0.5],
        );
        assert_eq!(x.len(), 4 * JOINT_STAGE_INPUTS);
        assert_eq!(&start[..JOINTS], &read(1.0));
        assert_eq!(&start[JOINTS..2 * JOINTS], &read(3.0));
        assert_eq!(&start[2 * JOINTS..3 * JOINTS], &read(4.0));
        assert_eq!(&start[3 * JOINTS..], &read(0.0));
    }

    #[test]
    fn slots_are_in_time_order_then_zeros() {
        assert_eq!(joint_stage_input_len(JOINTS), JOINT_STAGE_INPUTS);
        let (x, _) = joint_stage_inputs(&[1.0, 0.0], &reads(&[read(4.0), read(0.0)]), &[0.25]);
        assert_eq!(&x[..JOINTS], &read(0.0));
        assert_eq!(x[JOINTS..SLOT], [-0.25, 1.0]);
        assert_eq!(&x[SLOT..SLOT + JOINTS], &read(4.0));
        assert_eq!(x[SLOT + JOINTS..2 * SLOT], [0.75, 1.0]);
        assert!(x[2 * SLOT..JOINT_STAGE_SLOTS * SLOT]
            .iter()
            .all(|&v| v == 0.0));
        let tail = &x[JOINT_STAGE_SLOTS * SLOT..];
        assert_eq!(&tail[..JOINTS], &read(1.0));
        assert_eq!(tail[JOINTS], 0.25);
        assert!((tail[JOINTS + 1] - (std::f32::consts::PI * 0.25).sin()).abs() < 1e-6);
        assert!(
            (tail[JOINTS + 1 + JOINT_STAGE_FREQUENCIES] - (std::f32::consts::PI * 0.25).cos())
                .abs()
                < 1e-6
        );
    }

    #[test]
    fn more_glimpses_than_slots_show_the_nearest() {
        let times: Vec<f32> = (0..12).map(|i| i as f32 / 11.0).collect();
        let rows: Vec<_> = (0..12).map(|i| read(i as f32)).collect();
        let (x, _) = joint_stage_inputs(&times, &reads(&rows), &[1.0]);
        let first: Vec<f32> = x[..JOINTS].to_vec();
        assert_eq!(
            first,
            read(4.0),
            "the 8 nearest to the end are glimpses 4-11"
        );
        assert!(x[..JOINT_STAGE_SLOTS * SLOT]
            .chunks(SLOT)
            .all(|s| s[SLOT - 1] == 1.0));
    }

    #[test]
    fn any_joint_count() {
        let two = Joints::from_rows(&[[0.0f32, 1.0], [2.0, 3.0]]);
        let (x, start) = joint_stage_inputs(&[0.0, 1.0], &two, &[0.5]);
        assert_eq!(x.len(), joint_stage_input_len(2));
        assert_eq!(start, [1.0, 2.0]);
    }
}
