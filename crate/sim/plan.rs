use rand::RngExt;
use rand_pcg::Pcg64;
use rapier3d::math::Vector;

use super::arm::{ARM_JOINTS, FINGER_OPEN};
use super::ik::{GripperPose, Ik};
use super::scene::OBJECT_RADIUS;
use super::{Action, Trajectory};

/// Joint angles near the home pose (gripper above the table centre, pointing down): the
/// starting guess that puts IK on the elbow-up, wrist-down branch.
pub const HOME_GUESS: [f32; ARM_JOINTS] =
    [0.0, -1.2, 1.5, -1.87, -core::f32::consts::FRAC_PI_2, 0.0];
/// Where every episode starts: above the middle of the placement region.
pub const HOME: [f32; 3] = [0.0, 0.52, 0.40];
/// A performed trajectory's gripper column (the fingers' total travel, negative) above which
/// the gripper is commanded open (see [`Plan::from_trajectory`]).
pub const GRIPPER_OPEN: f32 = -0.03;
/// ... and below which it is commanded fully closed.
pub const GRIPPER_CLOSED: f32 = -0.06;

/// The scripted trajectory of one episode: per recorded step, the joint targets the motors
/// track and the gripper closure (0 open, 1 fully closed).
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Arm joint targets per step.
    pub joints: Vec<[f32; ARM_JOINTS]>,
    /// Gripper closure target per step, in [0, 1].
    pub closure: Vec<f32>,
}

/// One piece of a script: move the grasp point to `to` over `steps` steps (smoothstep easing)
/// while the closure goes linearly to `closure`.
struct Segment {
    to: GripperPose,
    steps: usize,
    closure: f32,
}

impl Plan {
    /// The plan for `action` with the object at `object` (x, y on the table); `rng` draws the
    /// segment durations and the free parameters (lift offset, push direction and distance).
    pub fn new(action: Action, object: [f32; 2], rng: &mut Pcg64) -> Plan {
        let [ox, oy] = object;
        let home = GripperPose {
            position: Vector::from(HOME),
            yaw: 0.0,
        };
        let segments = match action {
            Action::Grasp => {
                let yaw = rng.random_range(-0.4f32..0.4);
                let above = Vector::new(ox, oy, 0.20);
                let grasp = Vector::new(ox, oy, 0.05);
                let lift = Vector::new(
                    ox + rng.random_range(-0.06f32..0.06),
                    oy + rng.random_range(-0.06f32..0.06),
                    0.28,
                );
                vec![
                    Segment {
                        to: GripperPose {
                            position: above,
                            yaw,
                        },
                        steps: rng.random_range(14..=30),
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: grasp,
                            yaw,
                        },
                        steps: rng.random_range(8..=16),
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: grasp,
                            yaw,
                        },
                        steps: rng.random_range(6..=12),
                        closure: 1.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: lift,
                            yaw,
                        },
                        steps: rng.random_range(8..=24),
                        closure: 1.0,
                    },
                ]
            }
            Action::Move => {
                // Push towards the other side of the table, give or take 20 degrees.
                let side = if ox > 0.0 { core::f32::consts::PI } else { 0.0 };
                let angle = side + rng.random_range(-0.35f32..0.35);
                let dir = Vector::new(libm::cosf(angle), libm::sinf(angle), 0.0);
                let distance = rng.random_range(0.12f32..0.22);
                // Fingers open along the push direction: the leading finger does the pushing.
                let mut yaw = angle;
                if yaw > core::f32::consts::FRAC_PI_2 {
                    yaw -= core::f32::consts::PI;
                }
                let behind = Vector::new(ox, oy, 0.0) - dir * (OBJECT_RADIUS + FINGER_OPEN + 0.03);
                let start_high = behind + Vector::new(0.0, 0.0, 0.14);
                let start_low = behind + Vector::new(0.0, 0.0, 0.035);
                let end_low = start_low + dir * distance;
                // Back off while rising, so the leading finger does not drag the object up.
                let end_high = end_low - dir * 0.05 + Vector::new(0.0, 0.0, 0.16);
                vec![
                    Segment {
                        to: GripperPose {
                            position: start_high,
                            yaw,
                        },
                        steps: rng.random_range(14..=28),
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: start_low,
                            yaw,
                        },
                        steps: rng.random_range(8..=14),
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: end_low,
                            yaw,
                        },
                        steps: rng.random_range(24..=48),
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: end_high,
                            yaw,
                        },
                        steps: rng.random_range(6..=20),
                        closure: 0.0,
                    },
                ]
            }
        };
        Self::from_segments(home, &segments)
    }

    /// The motor targets that make the arm perform `trajectory`: its rows' angles, and the
    /// gripper commanded closed as the gripper column closes, read one step ahead (the
    /// fingers reach a closure a step after it is commanded). The column is the fingers'
    /// measured travel, not a command: an open gripper's leading finger is pushed in by up
    /// to about a centimetre when it pushes the object, and fingers closed on the object stop
    /// at about -0.09. So the closure is 0 up to [`GRIPPER_OPEN`], 1 from [`GRIPPER_CLOSED`]
    /// (the full closure squeezes, however far the fingers got), linear between.
    ///
    /// Replaying a recorded episode's joints so reproduces its outcome (the simulator's
    /// tests): the arm is deflected a little by contacts when recorded and again when
    /// replayed, which costs millimetres; a target lead to make up for the motors' lag only
    /// moved the path further from the recording (measured).
    pub fn from_trajectory(trajectory: &Trajectory) -> Plan {
        let rows = trajectory.rows();
        let last = rows.len() - 1;
        let joints = rows.iter().map(|r| std::array::from_fn(|i| r[i])).collect();
        let closure = (0..rows.len())
            .map(|k| {
                let gripper = rows[(k + 1).min(last)][ARM_JOINTS];
                ((gripper - GRIPPER_OPEN) / (GRIPPER_CLOSED - GRIPPER_OPEN)).clamp(0.0, 1.0)
            })
            .collect();
        Plan { joints, closure }
    }

    /// Number of recorded steps.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// True for a plan without steps (never produced by [`Plan::new`]).
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Interpolate the grasp point in Cartesian space and solve IK at every step.
    fn from_segments(start: GripperPose, segments: &[Segment]) -> Plan {
        let ik = Ik::default();
        let (mut q, _) = ik.solve(&start, HOME_GUESS);
        let mut plan = Plan {
            joints: vec![q],
            closure: vec![0.0],
        };
        let (mut from, mut closure) = (start, 0.0f32);
        for seg in segments {
            for k in 1..=seg.steps {
                let u = k as f32 / seg.steps as f32;
                let s = u * u * (3.0 - 2.0 * u);
                let pose = GripperPose {
                    position: from.position + (seg.to.position - from.position) * s,
                    yaw: from.yaw + (seg.to.yaw - from.yaw) * s,
                };
                q = ik.solve(&pose, q).0;
                plan.joints.push(q);
                plan.closure.push(closure + (seg.closure - closure) * u);
            }
            from = seg.to;
            closure = seg.closure;
        }
        plan
    }
}
