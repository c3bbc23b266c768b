use serde::Serialize;

use super::{Action, PushError};
use crate::data::Sequence;

/// What a performed action achieved, judged against the demonstration it imitates (the same
/// object placement): did the grasp lift the object and carry it where the demonstration did,
/// did the push land it where the demonstration did, was it a valid action of its kind at all
/// (a sampled future may be a good push of another length), and how far the gripper's path
/// strayed from the demonstration's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outcome {
    /// The action judged.
    #[serde(serialize_with = "action_name")]
    pub action: Action,
    /// Grasp: lifted at least [`Outcome::LIFT_CM`] and carried to within
    /// [`Outcome::CARRY_CM`] of the demonstration's final object position; push: ended within
    /// [`Outcome::PUSH_CM`] of it.
    pub success: bool,
    /// A valid action of its kind, wherever it ended: a grasp as for `success`; a push moved
    /// the object at least [`Outcome::PUSH_TRAVEL_CM`], within [`Outcome::PUSH_DIRECTION_DEG`]
    /// of the demonstration's direction (its first 30% shows it: the arm goes behind the
    /// object), and did not topple it.
    pub valid: bool,
    /// The object's horizontal travel from its first to its last position, cm.
    pub travel_cm: f32,
    /// A push: the angle between the object's travel and the demonstration's, degrees (`None`
    /// for a grasp, or when either object moved less than 1 mm).
    pub direction_error_deg: Option<f32>,
    /// The object's final height differs from its resting height by over
    /// [`Outcome::TOPPLE_CM`] while on the table (not lifted): it fell over.
    pub toppled: bool,
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
    /// A grasp succeeds when, lifted, the object ends this close to the demonstration's final
    /// position (it was carried where the demonstration carried it).
    pub const CARRY_CM: f32 = 5.0;
    /// A valid push moves the object at least this far, cm: the least any scripted push moves
    /// it (the script moves the gripper 12-22 cm from a start behind the object, which travels
    /// 2-3 cm less; least over 150 demonstrations of each arm, seeds 900000-900149: UR5 10.3,
    /// Panda 9.6).
    pub const PUSH_TRAVEL_CM: f32 = 9.5;
    /// A valid push moves the object within this angle of the demonstration's direction.
    pub const PUSH_DIRECTION_DEG: f32 = 10.0;
    /// An object on the table whose centre moved this far up or down fell over (the cylinder
    /// lying has its centre 1 cm lower than standing).
    pub const TOPPLE_CM: f32 = 0.5;

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
        let lifted = lift_cm >= Self::LIFT_CM;
        let success = match action {
            Action::Grasp => lifted && object_error_cm <= Self::CARRY_CM,
            Action::Move => object_error_cm <= Self::PUSH_CM,
        };
        let travel_cm = horizontal(first, last) * 100.0;
        let direction_error_deg = match action {
            Action::Grasp => None,
            Action::Move => angle_between(demonstrated.first()?, goal, first, last),
        };
        let toppled = !lifted && lift_cm.abs() > Self::TOPPLE_CM;
        let valid = match action {
            Action::Grasp => success,
            Action::Move => {
                travel_cm >= Self::PUSH_TRAVEL_CM
                    && direction_error_deg.is_some_and(|d| d <= Self::PUSH_DIRECTION_DEG)
                    && !toppled
            }
        };
        Some(Outcome {
            action,
            success,
            valid,
            travel_cm,
            direction_error_deg,
            toppled,
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
            (Action::Grasp, false) if self.lift_cm >= Self::LIFT_CM => format!(
                "lifted {:.0} cm, but carried it to {:.1} cm of the demonstration's spot",
                self.lift_cm, self.object_error_cm
            ),
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

/// Horizontal distance between `a` and `b`.
fn horizontal(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// The angle in degrees between the horizontal travels `a0 → a1` and `b0 → b1`; `None` when
/// either is under 1 mm.
fn angle_between(a0: &[f32; 3], a1: &[f32; 3], b0: &[f32; 3], b1: &[f32; 3]) -> Option<f32> {
    let (ax, ay, bx, by) = (a1[0] - a0[0], a1[1] - a0[1], b1[0] - b0[0], b1[1] - b0[1]);
    let (na, nb) = ((ax * ax + ay * ay).sqrt(), (bx * bx + by * by).sqrt());
    if na < 1e-3 || nb < 1e-3 {
        return None;
    }
    let cos = ((ax * bx + ay * by) / (na * nb)).clamp(-1.0, 1.0);
    Some(libm::acosf(cos).to_degrees())
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
    fn a_grasp_succeeds_when_lifted_ten_cm_near_the_spot_and_a_push_within_three() {
        let rest = [0.0, 0.5, 0.05];
        let demo = sequence(vec![rest, [0.0, 0.5, 0.19]], 0.0);
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
    fn a_grasp_must_carry_and_a_valid_push_need_not_land() {
        let rest = [0.0, 0.5, 0.05];
        let demo = sequence(vec![rest, [0.1, 0.5, 0.30]], 0.0);
        // Lifted, but 6 cm from where the demonstration carried it.
        let astray = sequence(vec![rest, [0.1, 0.56, 0.30]], 0.0);
        let o = Outcome::judge(Action::Grasp, &astray, &demo).unwrap();
        assert!(!o.success && !o.valid, "{o:?}");
        assert_eq!(
            o.summary(),
            "lifted 25 cm, but carried it to 6.0 cm of the demonstration's spot"
        );
        let carried = sequence(vec![rest, [0.1, 0.54, 0.30]], 0.0);
        let o = Outcome::judge(Action::Grasp, &carried, &demo).unwrap();
        assert!(
            o.success && o.valid && o.direction_error_deg.is_none(),
            "{o:?}"
        );

        // The demonstration pushed 20 cm along +x.
        let pushed = sequence(vec![rest, [0.2, 0.5, 0.05]], 0.0);
        let judge = |end: [f32; 3]| {
            Outcome::judge(Action::Move, &sequence(vec![rest, end], 0.0), &pushed).unwrap()
        };
        // 12 cm the same way: a valid push of another length, not a success.
        let shorter = judge([0.12, 0.5, 0.05]);
        assert!(shorter.valid && !shorter.success, "{shorter:?}");
        assert!((shorter.travel_cm - 12.0).abs() < 1e-3);
        assert!(shorter.direction_error_deg.unwrap() < 1e-3);
        // Too short, off by 20 degrees, or toppled: not a valid push.
        assert!(!judge([0.08, 0.5, 0.05]).valid);
        let (c, s) = (20f32.to_radians().cos(), 20f32.to_radians().sin());
        let aside = judge([0.15 * c, 0.5 + 0.15 * s, 0.05]);
        assert!(!aside.valid && (aside.direction_error_deg.unwrap() - 20.0).abs() < 0.01);
        let toppled = judge([0.15, 0.5, 0.04]);
        assert!(toppled.toppled && !toppled.valid, "{toppled:?}");
        // A push that lands is valid.
        assert!(judge([0.2, 0.51, 0.05]).valid);
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
