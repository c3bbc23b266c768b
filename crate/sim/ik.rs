use rapier3d::math::{Rotation, Vector};
use rapier3d::na::{Matrix6, Vector6};

use super::arm::{v, Arm, ARM_JOINTS};

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
    /// The link-6 rotation that realises this pose.
    pub fn rotation(&self) -> Rotation {
        let down = Vector::new(0.0, 0.0, -1.0);
        let closing = Vector::new(libm::cosf(self.yaw), libm::sinf(self.yaw), 0.0);
        // Zero-configuration axes: tool -x, closing +z, their cross product +y.
        let ex = -down;
        let ey = down.cross(closing);
        let ez = closing;
        Rotation::from_mat3(&rapier3d::glamx::Mat3::from_cols(ex, ey, ez))
    }
}

/// Damped-least-squares inverse kinematics on [`Arm`]'s chain.
///
/// Deterministic: a fixed number of f32 operations in a fixed order, so native and wasm agree
/// bit for bit. Warm-started from the previous solution, so consecutive targets stay on one
/// branch (elbow up, wrist down) and the joint path is smooth.
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
    /// Joint angles reaching `target`, starting from `q`. Returns the angles and the final
    /// error norm (metres + radians), which is small when the target is reachable.
    pub fn solve(
        &self,
        target: &GripperPose,
        mut q: [f32; ARM_JOINTS],
    ) -> ([f32; ARM_JOINTS], f32) {
        let goal_rot = target.rotation();
        let mut err = f32::INFINITY;
        for _ in 0..self.iterations {
            let e = pose_error(&q, target.position, goal_rot);
            err = e.norm();
            if err < self.tolerance {
                break;
            }
            let j = jacobian(&q);
            let jjt = j * j.transpose() + Matrix6::identity() * (self.damping * self.damping);
            let Some(inv) = jjt.try_inverse() else { break };
            let dq = j.transpose() * (inv * e);
            for (qi, d) in q.iter_mut().zip(dq.iter()) {
                *qi = (*qi + d.clamp(-0.3, 0.3)).clamp(-Arm::LIMIT, Arm::LIMIT);
            }
        }
        (q, err)
    }
}

/// 6-D pose error: position difference, then the rotation error 0.5 Σ cᵢ × dᵢ over the columns.
fn pose_error(q: &[f32; ARM_JOINTS], goal: Vector, goal_rot: Rotation) -> Vector6<f32> {
    let (p, rot) = Arm::grasp_frame(q);
    let dp = goal - p;
    let mut w = Vector::ZERO;
    for axis in [Vector::X, Vector::Y, Vector::Z] {
        w += (rot * axis).cross(goal_rot * axis);
    }
    w *= 0.5;
    Vector6::new(dp.x, dp.y, dp.z, w.x, w.y, w.z)
}

/// Geometric Jacobian of the grasp point: column i is (aᵢ × (p − oᵢ), aᵢ).
fn jacobian(q: &[f32; ARM_JOINTS]) -> Matrix6<f32> {
    let poses = Arm::link_poses(q);
    let (p, _) = Arm::grasp_frame(q);
    let mut j = Matrix6::zeros();
    for (i, pose) in poses.iter().enumerate() {
        let a = pose.rotation * v(Arm::JOINT_AXES[i]);
        let lin = a.cross(p - pose.translation);
        j.set_column(i, &Vector6::new(lin.x, lin.y, lin.z, a.x, a.y, a.z));
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reaches_points_over_the_table() {
        let ik = Ik::default();
        let mut q = super::super::plan::HOME_GUESS;
        for (x, y, z) in [
            (0.0, 0.55, 0.4),
            (0.15, 0.45, 0.05),
            (-0.15, 0.65, 0.05),
            (0.0, 0.6, 0.3),
        ] {
            let target = GripperPose {
                position: Vector::new(x, y, z),
                yaw: 0.0,
            };
            let (sol, err) = ik.solve(&target, q);
            assert!(err < 1e-3, "target ({x}, {y}, {z}): error {err}");
            let (p, _) = Arm::grasp_frame(&sol);
            assert!((p - target.position).length() < 1e-3);
            q = sol;
        }
    }
}
