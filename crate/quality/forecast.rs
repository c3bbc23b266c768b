//! The benchmark's measures of a forecast given as byte frames, as the page draws it (live mode).
use super::accumulator::Guess;
use super::{Accumulator, Quality};

/// Scores `frames` (RGB bytes, steps × S × S × 3) and `joints` (steps × `d`) guessed for
/// a run of steps against the true `true_frames` and `true_joints` of the same steps, every
/// step scored (joint RMSE over the arm joints in radians, image MSE in [0, 1], object IoU).
/// Fails, naming the argument, when the layouts disagree or there is no step.
pub fn score_steps(
    true_frames: &[u8],
    true_joints: &[f32],
    frames: &[u8],
    joints: &[f32],
    d: usize,
) -> Result<Quality, String> {
    let steps = true_joints.len() / d.max(1);
    if d == 0 || steps == 0 || true_joints.len() % d != 0 {
        return Err(format!(
            "trueJoints: {} values, expected a positive multiple of {d} (the joint values a step)",
            true_joints.len()
        ));
    }
    if joints.len() != true_joints.len() {
        return Err(format!(
            "joints: {} values for {steps} steps, expected {}",
            joints.len(),
            true_joints.len()
        ));
    }
    let px = true_frames.len() / steps;
    if px == 0 || px % 3 != 0 || px * steps != true_frames.len() {
        return Err(format!(
            "trueFrames: {} bytes, expected {steps} RGB frames",
            true_frames.len()
        ));
    }
    if frames.len() != true_frames.len() {
        return Err(format!(
            "frames: {} bytes, expected {} ({steps} frames like trueFrames')",
            frames.len(),
            true_frames.len()
        ));
    }
    let mut acc = Accumulator::default();
    acc.begin_sequence();
    let mut guess = vec![0.0f32; px];
    for k in 0..steps {
        for (g, &v) in guess.iter_mut().zip(&frames[k * px..(k + 1) * px]) {
            *g = v as f32 / 255.0;
        }
        let truth = &true_joints[k * d..(k + 1) * d];
        let guess = Guess {
            frame: &guess,
            joints: &joints[k * d..(k + 1) * d],
            sigma: None,
        };
        acc.add(
            guess,
            &true_frames[k * px..(k + 1) * px],
            truth,
            false,
            true,
        );
    }
    Ok(acc.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;

    #[test]
    fn scores_the_difference_and_names_bad_layouts() {
        // Two steps of 2 × 2 frames: the guess is off by 51/255 = 0.2 on every pixel value and
        // by 0.1 rad on every arm joint.
        let truth = vec![100u8; 2 * 12];
        let guess = vec![151u8; 2 * 12];
        let joints = vec![0.5f32; 2 * JOINTS];
        let guessed: Vec<f32> = joints.iter().map(|v| v + 0.1).collect();
        let q = score_steps(&truth, &joints, &guess, &guessed, JOINTS).unwrap();
        assert_eq!(q.steps, 2);
        assert!((q.image_mse - 0.04).abs() < 1e-6, "{}", q.image_mse);
        assert!((q.joint_rmse - 0.1).abs() < 1e-6, "{}", q.joint_rmse);
        assert!(score_steps(&truth, &joints, &guess[1..], &guessed, JOINTS)
            .unwrap_err()
            .starts_with("frames:"));
        assert!(score_steps(&truth, &joints, &guess, &guessed[1..], JOINTS)
            .unwrap_err()
            .starts_with("joints:"));
        assert!(score_steps(&truth[1..], &joints, &guess, &guessed, JOINTS)
            .unwrap_err()
            .starts_with("trueFrames:"));
        assert!(score_steps(&truth, &[], &guess, &[], JOINTS)
            .unwrap_err()
            .starts_with("trueJoints:"));
    }
}
