use core::ops::RangeInclusive;

use rand::RngExt;
use rand_pcg::Pcg64;
use rapier3d::math::Vector;

use super::chain::{Chain, FINGER_OPEN};
use super::ik::{GripperPose, Ik};
use super::plan::HOME;
use super::scene::OBJECT_RADIUS;
use super::ur5::UR5;
#[cfg(doc)]
use super::Simulator;
use super::{Action, Plan};

/// A scripted action before it is timed: from home, the grasp point moves through segments,
/// each to a pose (smoothstep easing) while the closure goes linearly to its value, over a
/// duration drawn from its range. An episode draws the durations ([`Simulator::script`]);
/// an experiment may time the same motion otherwise (`experiments/push_oracle.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct Script {
    /// Where the grasp point starts.
    pub home: GripperPose,
    /// The segments in order.
    pub segments: Vec<Segment>,
}

/// One piece of a [`Script`].
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// The pose the segment ends at.
    pub to: GripperPose,
    /// The steps it may take (the script draws one uniformly).
    pub steps: RangeInclusive<usize>,
    /// The gripper closure it ends at (0 open, 1 closed).
    pub closure: f32,
}

impl Script {
    /// The script of `action` with the object at `object` (x, y on the table); `rng` draws
    /// the free parameters (lift offset, push direction and distance).
    pub fn new(action: Action, object: [f32; 2], rng: &mut Pcg64) -> Script {
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
                        steps: 14..=30,
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: grasp,
                            yaw,
                        },
                        steps: 8..=16,
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: grasp,
                            yaw,
                        },
                        steps: 6..=12,
                        closure: 1.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: lift,
                            yaw,
                        },
                        steps: 8..=24,
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
                        steps: 14..=28,
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: start_low,
                            yaw,
                        },
                        steps: 8..=14,
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: end_low,
                            yaw,
                        },
                        steps: 24..=48,
                        closure: 0.0,
                    },
                    Segment {
                        to: GripperPose {
                            position: end_high,
                            yaw,
                        },
                        steps: 6..=20,
                        closure: 0.0,
                    },
                ]
            }
        };
        Script { home, segments }
    }

    /// Each segment's duration, drawn uniformly from its range in order.
    pub fn draw_durations(&self, rng: &mut Pcg64) -> Vec<usize> {
        self.segments
            .iter()
            .map(|s| rng.random_range(s.steps.clone()))
            .collect()
    }

    /// The grasp point's pose and the closure at step `step` (fractional steps in between) of
    /// the script timed with `durations` (one per segment); past the end, the last pose.
    pub fn at(&self, durations: &[usize], step: f32) -> (GripperPose, f32) {
        let (mut from, mut closure, mut start) = (self.home, 0.0f32, 0.0f32);
        for (seg, &steps) in self.segments.iter().zip(durations) {
            let end = start + steps as f32;
            if step <= end {
                let u = if steps == 0 {
                    1.0
                } else {
                    ((step - start) / steps as f32).clamp(0.0, 1.0)
                };
                let s = u * u * (3.0 - 2.0 * u);
                let pose = GripperPose {
                    position: from.position + (seg.to.position - from.position) * s,
                    yaw: from.yaw + (seg.to.yaw - from.yaw) * s,
                };
                return (pose, closure + (seg.closure - closure) * u);
            }
            (from, closure, start) = (seg.to, seg.closure, end);
        }
        (from, closure)
    }

    /// The UR5's plan of the script timed with `durations` (see [`Script::plan_on`]).
    pub fn plan(&self, durations: &[usize]) -> Plan {
        self.plan_on(&UR5, durations)
    }

    /// `chain`'s plan of the script timed with `durations` (one per segment): the grasp point
    /// interpolated in Cartesian space and IK solved at every step, warm-started from the
    /// step before so that the joints stay on one branch.
    pub fn plan_on<const N: usize>(&self, chain: &Chain<N>, durations: &[usize]) -> Plan<N> {
        let ik = Ik::default();
        let (mut q, _) = ik.solve(chain, &self.home, chain.home_guess);
        let mut plan = Plan {
            joints: vec![q],
            closure: vec![0.0],
        };
        let steps: usize = durations.iter().take(self.segments.len()).sum();
        for k in 1..=steps {
            let (pose, closure) = self.at(durations, k as f32);
            q = ik.solve(chain, &pose, q).0;
            plan.joints.push(q);
            plan.closure.push(closure);
        }
        plan
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{episode, Simulator};

    #[test]
    fn a_timed_script_passes_its_poses_and_is_the_episodes_plan() {
        for action in [Action::Grasp, Action::Move] {
            let seed = 11;
            let object = Simulator::placement(seed);
            let (script, durations) = Simulator::script(action, object, seed);
            for (segment, range) in durations
                .iter()
                .zip(script.segments.iter().map(|s| &s.steps))
            {
                assert!(
                    range.contains(segment),
                    "{action}: {segment} steps outside {range:?}"
                );
            }
            let mut end = 0;
            for (segment, &d) in script.segments.iter().zip(&durations) {
                end += d;
                let (pose, closure) = script.at(&durations, end as f32);
                assert!((pose.position - segment.to.position).length() < 1e-6);
                assert_eq!(closure, segment.closure);
            }
            let (past, _) = script.at(&durations, end as f32 + 5.0);
            assert_eq!(past, script.segments.last().unwrap().to);
            let plan = script.plan(&durations);
            assert_eq!(plan.len(), end + 1);
            // The episode records one step per planned step.
            assert_eq!(episode(action, seed, 64).unwrap().len(), plan.len());
            // Another timing of the same script: the same poses, a different length.
            let slower: Vec<usize> = durations.iter().map(|d| d + 2).collect();
            assert_eq!(script.plan(&slower).len(), plan.len() + 2 * durations.len());
        }
    }
}
