use rapier3d::math::{Pose, Rotation, Vector};

use super::render::Primitive;
use super::Arm;

/// Distance from the flange to the grasp point (between the fingertips), along the tool axis.
pub const GRASP_DEPTH: f32 = 0.105;
/// Finger half-gap when the gripper is open.
pub const FINGER_OPEN: f32 = 0.085;
/// How far each finger may travel towards the centre.
pub const FINGER_TRAVEL: f32 = 0.08;

/// An arm's kinematic chain of `N` revolute joints in its zero configuration, in the arm-base
/// frame (z up, y forward from the base towards the table centre, x to the right seen from the
/// camera), with the parallel gripper both arms carry.
///
/// At q = 0 every link frame is aligned with the world and sits on its joint, so the same
/// numbers describe the rapier multibody (anchors, axes) and the forward kinematics used by IK.
/// The simulator is generic over `N`, so each arm compiles to its own fixed-size arithmetic.
#[derive(Debug, Clone, Copy)]
pub struct Chain<const N: usize> {
    /// The arm this chain is.
    pub arm: Arm,
    /// Joint points at q = 0.
    pub joint_points: [[f32; 3]; N],
    /// Joint axes at q = 0.
    pub joint_axes: [[f32; 3]; N],
    /// Joint limits (radians): joint `i` within ±`limits[i]`.
    pub limits: [f32; N],
    /// Link masses (kg); the motors are acceleration-based, so they matter only in contacts.
    pub masses: [f32; N],
    /// The flange (tool mount) at q = 0.
    pub flange: [f32; 3],
    /// Tool axis (flange → fingertips) at q = 0.
    pub tool_axis: [f32; 3],
    /// Finger closing axis at q = 0 (perpendicular to the tool axis).
    pub closing_axis: [f32; 3],
    /// A finger's half extents at q = 0 (along the world axes).
    pub finger_half: [f32; 3],
    /// Joint angles near the home pose (gripper above the table centre, pointing down): the
    /// starting guess that puts IK on one branch (elbow up, wrist down).
    pub home_guess: [f32; N],
    /// Gain of the IK's null-space pull towards `home_guess`: what keeps a redundant arm's
    /// spare joint from drifting (0 for an arm without redundancy).
    pub rest_gain: f32,
    /// The solids of link `i` (0 = base) at q = 0, in world coordinates.
    pub link_parts: fn(usize) -> Vec<Primitive>,
}

impl<const N: usize> Chain<N> {
    /// Offset of joint `i`'s point from its parent link's origin (joint `i-1`'s point).
    pub fn anchor(&self, i: usize) -> Vector {
        let p = v(self.joint_points[i]);
        if i == 0 {
            p
        } else {
            p - v(self.joint_points[i - 1])
        }
    }

    /// World pose of every link (1..=N) for joint angles `q`, base at the origin.
    pub fn link_poses(&self, q: &[f32; N]) -> [Pose; N] {
        let mut poses = [Pose::IDENTITY; N];
        let mut parent = Pose::IDENTITY;
        for i in 0..N {
            let local = Pose::from_parts(
                self.anchor(i),
                Rotation::from_axis_angle(v(self.joint_axes[i]), q[i]),
            );
            parent *= local;
            poses[i] = parent;
        }
        poses
    }

    /// The grasp point in the last link's frame.
    pub fn grasp_offset(&self) -> Vector {
        v(self.flange) - v(self.joint_points[N - 1]) + v(self.tool_axis) * GRASP_DEPTH
    }

    /// Grasp point and tool frame for joint angles `q`: (grasp point, last link's rotation).
    pub fn grasp_frame(&self, q: &[f32; N]) -> (Vector, Rotation) {
        let last = self.link_poses(q)[N - 1];
        let flange = last * (v(self.flange) - v(self.joint_points[N - 1]));
        let tool = last.rotation * v(self.tool_axis);
        (flange + tool * GRASP_DEPTH, last.rotation)
    }
}

/// Array to vector.
pub fn v(a: [f32; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}
