use rapier3d::math::{Rotation, Vector};
use rapier3d::na::{Matrix6, SMatrix, SVector, Vector6};

use super::chain::{v, Chain};
use super::Arm;

/// A gripper target: grasp point and orientation (tool pointing down, fingers closing along
/// a horizontal direction at angle `yaw` from the x axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripperPose {
    /// Grasp point (between the fingertips), arm-base frame.
    pub position: Vector,
    /// Angle of the finger closing direction in the table plane, radians.
    pub yaw: f32,
}

impl GripperPose {
    /// The UR5's last-link rotation that realises this pose.
    pub fn rotation(&self) -> Rotation {
        let down = Vector::new(0.0, 0.0, -1.0);
        let closing = Vector::new(libm::cosf(self.yaw), libm::sinf(self.yaw), 0.0);
        // Zero-configuration axes: tool -x, closing +z, their cross product +y.
        let ex = -down;
        let ey = down.cross(closing);
        let ez = closing;
        Rotation::from_mat3(&rapier3d::glamx::Mat3::from_cols(ex, ey, ez))
    }

    /// The last-link rotation of `chain` that realises this pose: the one taking its
    /// zero-configuration tool and closing axes onto the pose's (the UR5's as
    /// [`rotation`](GripperPose::rotation) computes it).
    pub fn rotation_on<const N: usize>(&self, chain: &Chain<N>) -> Rotation {
        if chain.arm == Arm::Ur5 {
            return self.rotation();
        }
        use rapier3d::glamx::Mat3;
        let down = Vector::new(0.0, 0.0, -1.0);
        let closing = Vector::new(libm::cosf(self.yaw), libm::sinf(self.yaw), 0.0);
        let (tool0, closing0) = (v(chain.tool_axis), v(chain.closing_axis));
        let goal = Mat3::from_cols(down, closing, down.cross(closing));
        let zero = Mat3::from_cols(tool0, closing0, tool0.cross(closing0));
        Rotation::from_mat3(&(goal * zero.transpose()))
    }
}

/// Damped-least-squares inverse kinematics on a [`Chain`].
///
/// Deterministic: a fixed number of f32 operations in a fixed order, so native and wasm agree
/// bit for bit. Warm-started from the previous solution, so consecutive targets stay on one
/// branch (elbow up, wrist down) and the joint path is smooth. A redundant chain's spare
/// motion is pulled towards its home posture in the Jacobian's null space (once a solve,
/// so the pull cannot hold the tool off its target), so that the elbow does not wander
/// while the grasp point follows the target.
#[derive(Debug, Clone, Copy)]
pub struct Ik {
    /// Damping λ: trades accuracy near singularities for bounded joint steps.
    pub damping: f32,
    /// Iterations at most per solve.
    pub iterations: usize,
    /// Stop when the pose error norm falls below this.
    pub tolerance: f32,
}

impl Default for Ik {
    fn default() -> Self {
        Ik {
            damping: 0.05,
            iterations: 60,
            tolerance: 1e-5,
        }
    }
}

impl Ik {
    /// Joint angles of `chain` reaching `target`, starting from `q`. Returns the angles and
    /// the final error norm (metres + radians), which is small when the target is reachable.
    pub fn solve<const N: usize>(
        &self,
        chain: &Chain<N>,
        target: &GripperPose,
        mut q: [f32; N],
    ) -> ([f32; N], f32) {
        let goal_rot = target.rotation_on(chain);
        let mut err = f32::INFINITY;
        for iteration in 0..self.iterations {
            let e = pose_error(chain, &q, target.position, goal_rot);
            err = e.norm();
            if err < self.tolerance {
                break;
            }
            let j = jacobian(chain, &q);
            let jjt = j * j.transpose() + Matrix6::identity() * (self.damping * self.damping);
            let Some(inv) = jjt.try_inverse() else { break };
            let mut dq = j.transpose() * (inv * e);
            if chain.rest_gain > 0.0 && iteration == 0 {
                // (I - J⁺J) z: the pull z towards home, less what of it would move the tool.
                // Once a solve: the damped J⁺ leaks a little of it into the tool's pose,
                // which the iterations after it then take out.
                let z = SVector::<f32, N>::from_fn(|i, _| {
                    chain.rest_gain * (chain.home_guess[i] - q[i])
                });
                dq += z - j.transpose() * (inv * (j * z));
            }
            for ((qi, d), limit) in q.iter_mut().zip(dq.iter()).zip(chain.limits) {
                *qi = (*qi + d.clamp(-0.3, 0.3)).clamp(-limit, limit);
            }
        }
        (q, err)
    }
}

/// 6-D pose error: position difference, then the rotation error 0.5 Σ cᵢ × dᵢ over the columns.
fn pose_error<const N: usize>(
    chain: &Chain<N>,
    q: &[f32; N],
    goal: Vector,
    goal_rot: Rotation,
) -> Vector6<f32> {
    let (p, rot) = chain.grasp_frame(q);
    let dp = goal - p;
    let mut w = Vector::ZERO;
    for axis in [Vector::X, Vector::Y, Vector::Z] {
        w += (rot * axis).cross(goal_rot * axis);
    }
    w *= 0.5;
    Vector6::new(dp.x, dp.y, dp.z, w.x, w.y, w.z)
}

/// Geometric Jacobian of the grasp point: column i is (aᵢ × (p − oᵢ), aᵢ).
fn jacobian<const N: usize>(chain: &Chain<N>, q: &[f32; N]) -> SMatrix<f32, 6, N> {
    let poses = chain.link_poses(q);
    let (p, _) = chain.grasp_frame(q);
    let mut j = SMatrix::<f32, 6, N>::zeros();
    for (i, pose) in poses.iter().enumerate() {
        let a = pose.rotation * v(chain.joint_axes[i]);
        let lin = a.cross(p - pose.translation);
        j.set_column(i, &Vector6::new(lin.x, lin.y, lin.z, a.x, a.y, a.z));
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Action, Script, Simulator, PANDA, UR5};

    /// Targets over the placement region at grasping and travelling heights, turned.
    const TARGETS: [(f32, f32, f32, f32); 6] = [
        (0.0, 0.55, 0.4, 0.0),
        (0.15, 0.45, 0.05, 0.3),
        (-0.15, 0.65, 0.05, -0.3),
        (0.0, 0.6, 0.3, 0.0),
        (0.3, 0.7, 0.035, 0.35),
        (-0.3, 0.45, 0.035, -0.35),
    ];

    fn reaches<const N: usize>(chain: &Chain<N>) {
        let ik = Ik::default();
        let mut q = chain.home_guess;
        for (x, y, z, yaw) in TARGETS {
            let target = GripperPose {
                position: Vector::new(x, y, z),
                yaw,
            };
            let (sol, err) = ik.solve(chain, &target, q);
            assert!(
                err < 1e-3,
                "{}: target ({x}, {y}, {z}): error {err}",
                chain.arm
            );
            let (p, rot) = chain.grasp_frame(&sol);
            assert!((p - target.position).length() < 1e-3);
            // The tool points down.
            let tool = rot * v(chain.tool_axis);
            assert!(tool.z < -0.999, "{}: tool {tool:?}", chain.arm);
            for (i, (qi, limit)) in sol.iter().zip(chain.limits).enumerate() {
                assert!(qi.abs() <= limit, "{}: joint {i} at {qi}", chain.arm);
            }
            q = sol;
        }
    }

    #[test]
    fn reaches_points_over_the_table() {
        reaches(&UR5);
        reaches(&PANDA);
    }

    #[test]
    fn the_panda_follows_every_scripted_pose_without_wandering() {
        for seed in 0..12 {
            for action in Action::ALL {
                let object = Simulator::placement(seed);
                let (script, durations): (Script, Vec<usize>) =
                    Simulator::script(action, object, seed);
                let plan = script.plan_on(&PANDA, &durations);
                let steps: usize = durations.iter().sum();
                for k in 0..=steps {
                    let (pose, _) = script.at(&durations, k as f32);
                    let (p, _) = PANDA.grasp_frame(&plan.joints[k]);
                    let miss = (p - pose.position).length();
                    assert!(miss < 2e-3, "{action} seed {seed} step {k}: {miss} m off");
                    // No joint flips between steps: the path is smooth.
                    if k > 0 {
                        for (a, b) in plan.joints[k].iter().zip(&plan.joints[k - 1]) {
                            assert!((a - b).abs() < 0.2, "{action} seed {seed} step {k}");
                        }
                    }
                }
            }
        }
    }
}
