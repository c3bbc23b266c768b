use serde::Serialize;

use super::{Action, PushError};
use crate::data::Sequence;

/// What a performed action achieved, judged against the demonstration it imitates (the same
/// object placement): did the grasp lift the object, did the push land it where the
/// demonstration did, and how far the gripper's path strayed from the demonstration's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outcome {
    /// The action judged.
    #[serde(serialize_with = "action_name")]
    pub action: Action,
    /// Grasp: lifted at least [`Outcome::LIFT_CM`]; push: ended within [`Outcome::PUSH_CM`]
    /// of the demonstration's final object position.
    pub success: bool,
    /// The object's final height above where it rested at the first step, cm.
    pub lift_cm: f32,
    /// The object's final position against the demonstration's, cm.
    pub object_error_cm: f32,
    /// A push's object error resolved along the demonstration's push (the object's horizontal
    /// travel; negative: short of the spot) and across it (positive: to the push's left), cm:
    /// pushed too little or too far, or knocked aside. `None` for a grasp (or a
    /// demonstration whose object did not travel).
    pub push_error_cm: Option<PushError>,
    /// The mean distance between the grasp point and the demonstration's at the same phase, cm.
    pub path_error_cm: f32,
}

fn action_name<S: serde::Serializer>(action: &Action, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(action.name())
}

impl Outcome {
    /// A grasp succeeds when the object ends at least this high above its resting height.
    pub const LIFT_CM: f32 = 10.0;
    /// A push succeeds when the object ends this close to the demonstration's final position.
    pub const PUSH_CM: f32 = 3.0;

    /// Judges `performed` (an episode of `action`) against `demonstration`; the two are
    /// compared at equal phase, so their lengths may differ. `None` when either is empty or
    /// lacks its object or end-effector track.
    pub fn judge(action: Action, performed: &Sequence, demonstration: &Sequence) -> Option<Self> {
        let (performed_object, demonstrated) =
            (performed.object.as_ref()?, demonstration.object.as_ref()?);
        let (performed_endpoint, demonstrated_endpoint) = (
            performed.endpoint.as_ref()?,
            demonstration.endpoint.as_ref()?,
        );
        let (first, last) = (performed_object.first()?, performed_object.last()?);
        let goal = demonstrated.last()?;
        let lift_cm = (last[2] - first[2]) * 100.0;
        let object_error_cm = distance(last, goal) * 100.0;
        let push_error_cm = match action {
            Action::Grasp => None,
            Action::Move => PushError::of(demonstrated.first()?, goal, last),
        };
        let n = performed.len();
        let path: f32 = (0..n)
            .map(|k| {
                let phase = if n > 1 {
                    k as f32 / (n - 1) as f32
                } else {
                    0.0
                };
                let ours = &performed_endpoint[k];
                let theirs = at_phase(demonstrated_endpoint, phase);
                distance(&[ours[0], ours[1], ours[2]], &theirs)
            })
            .sum();
        let success = match action {
            Action::Grasp => lift_cm >= Self::LIFT_CM,
            Action::Move => object_error_cm <= Self::PUSH_CM,
        };
        Some(Outcome {
            action,
            success,
            lift_cm,
            object_error_cm,
            push_error_cm,
            path_error_cm: path / n as f32 * 100.0,
        })
    }

    /// One line for people: "lifted 21 cm", "pushed to 1.4 cm of the demonstration's spot",
    /// or what went wrong.
    pub fn summary(&self) -> String {
        match (self.action, self.success) {
            (Action::Grasp, true) => format!("lifted {:.0} cm", self.lift_cm),
            (Action::Grasp, false) => format!("missed: the object rose {:.1} cm", self.lift_cm),
            (Action::Move, true) => format!(
                "pushed to {:.1} cm of the demonstration's spot",
                self.object_error_cm
            ),
            (Action::Move, false) => {
                let why = self
                    .push_error_cm
                    .map_or(String::new(), |e| format!(": {e}"));
                format!(
                    "missed: the object ended {:.1} cm from the demonstration's spot{why}",
                    self.object_error_cm
                )
            }
        }
    }
}

fn distance(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let d: f32 = (0..3).map(|i| (a[i] - b[i]) * (a[i] - b[i])).sum();
    d.sqrt()
}

/// The first three values of `rows` (positions) linearly interpolated at `phase` in [0, 1].
fn at_phase<const N: usize>(rows: &[[f32; N]], phase: f32) -> [f32; 3] {
    let x = phase.clamp(0.0, 1.0) * (rows.len() - 1) as f32;
    let lo = (x.floor() as usize).min(rows.len() - 1);
    let hi = (lo + 1).min(rows.len() - 1);
    let w = x - lo as f32;
    std::array::from_fn(|i| rows[lo][i] + w * (rows[hi][i] - rows[lo][i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Joints;

    fn sequence(object: Vec<[f32; 3]>, x: f32) -> Sequence {
        let n = object.len();
        Sequence {
            image_size: 1,
            joints: Joints::from_rows(&vec![[0.0; 7]; n]),
            endpoint: Some(
                (0..n)
                    .map(|k| [x + k as f32 * 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
                    .collect(),
            ),
            object: Some(object),
            frames: vec![0; n * 3],
        }
    }

    #[test]
    fn a_grasp_succeeds_when_lifted_ten_cm_and_a_push_within_three() {
        let rest = [0.0, 0.5, 0.05];
        let demo = sequence(vec![rest, [0.0, 0.5, 0.30]], 0.0);
        let lifted = sequence(vec![rest, [0.01, 0.5, 0.16]], 0.02);
        let o = Outcome::judge(Action::Grasp, &lifted, &demo).unwrap();
        assert!(o.success && (o.lift_cm - 11.0).abs() < 1e-3, "{o:?}");
        assert!((o.path_error_cm - 2.0).abs() < 1e-3, "{o:?}");
        assert_eq!(o.summary(), "lifted 11 cm");
        let low = sequence(vec![rest, [0.0, 0.5, 0.14]], 0.0);
        assert!(!Outcome::judge(Action::Grasp, &low, &demo).unwrap().success);

        let pushed = sequence(vec![rest, [0.2, 0.5, 0.05]], 0.0);
        let near = sequence(vec![rest, [0.2, 0.529, 0.05]], 0.0);
        let far = sequence(vec![rest, [0.2, 0.531, 0.05]], 0.0);
        assert!(
            Outcome::judge(Action::Move, &near, &pushed)
                .unwrap()
                .success
        );
        let o = Outcome::judge(Action::Move, &far, &pushed).unwrap();
        assert!(
            !o.success && (o.object_error_cm - 3.1).abs() < 1e-3,
            "{o:?}"
        );
    }

    #[test]
    fn paths_are_compared_at_equal_phase() {
        // Three steps against two: the middle step meets the demonstration half-way.
        let demo = sequence(vec![[0.0; 3]; 2], 0.0);
        let performed = sequence(vec![[0.0; 3]; 3], 0.0);
        let o = Outcome::judge(Action::Move, &performed, &demo).unwrap();
        // Ours at x = 0, 0.01, 0.02; theirs at 0, 0.005, 0.01.
        assert!((o.path_error_cm - 0.5).abs() < 1e-3, "{o:?}");
        assert!(Outcome::judge(Action::Move, &sequence(vec![], 0.0), &demo).is_none());
    }
}
