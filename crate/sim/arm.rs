use rapier3d::math::{Pose, Rotation, Vector};

/// Arm joints (6 revolute) before the gripper.
pub const ARM_JOINTS: usize = 6;

/// UR5 Denavit-Hartenberg lengths (metres): shoulder height, upper arm, forearm, wrist offsets.
const D1: f32 = 0.089_159;
const A2: f32 = 0.425;
const A3: f32 = 0.392_25;
const D4: f32 = 0.109_15;
const D5: f32 = 0.094_65;
const D6: f32 = 0.0823;

/// Distance from the flange to the grasp point (between the fingertips), along the tool axis.
pub const GRASP_DEPTH: f32 = 0.105;
/// Finger half-gap when the gripper is open.
pub const FINGER_OPEN: f32 = 0.085;
/// How far each finger may travel towards the centre.
pub const FINGER_TRAVEL: f32 = 0.08;

/// The UR-like arm's kinematic chain in its zero configuration, in the arm-base frame
/// (z up, y forward from the base towards the table centre, x to the right seen from the camera).
///
/// At q = 0 every link frame is aligned with the world and sits on its joint, so the same
/// numbers describe the rapier multibody (anchors, axes) and the forward kinematics used by IK.
#[derive(Debug, Clone, Copy)]
pub struct Arm;

impl Arm {
    /// Joint points at q = 0 (the UR5 DH chain, base turned so the stretched arm points along +y).
    pub const JOINT_POINTS: [[f32; 3]; ARM_JOINTS] = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, D1],
        [0.0, A2, D1],
        [0.0, A2 + A3, D1],
        [-D4, A2 + A3, D1],
        [-D4, A2 + A3, D1 - D5],
    ];
    /// Joint axes at q = 0.
    pub const JOINT_AXES: [[f32; 3]; ARM_JOINTS] = [
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
        [-1.0, 0.0, 0.0],
    ];
    /// The flange (tool mount) at q = 0.
    pub const FLANGE: [f32; 3] = [-D4 - D6, A2 + A3, D1 - D5];
    /// Tool axis (flange → fingertips) at q = 0.
    pub const TOOL_AXIS: [f32; 3] = [-1.0, 0.0, 0.0];
    /// Finger closing axis at q = 0 (perpendicular to the tool axis).
    pub const CLOSING_AXIS: [f32; 3] = [0.0, 0.0, 1.0];
    /// Joint limits (radians), all joints alike: the UR's ±2π.
    pub const LIMIT: f32 = 2.0 * core::f32::consts::PI;

    /// Offset of joint `i`'s point from its parent link's origin (joint `i-1`'s point).
    pub fn anchor(i: usize) -> Vector {
        let p = v(Self::JOINT_POINTS[i]);
        if i == 0 {
            p
        } else {
            p - v(Self::JOINT_POINTS[i - 1])
        }
    }

    /// World pose of every link (1..=6) for joint angles `q`, base at the origin.
    pub fn link_poses(q: &[f32; ARM_JOINTS]) -> [Pose; ARM_JOINTS] {
        let mut poses = [Pose::IDENTITY; ARM_JOINTS];
        let mut parent = Pose::IDENTITY;
        for i in 0..ARM_JOINTS {
            let local = Pose::from_parts(
                Self::anchor(i),
                Rotation::from_axis_angle(v(Self::JOINT_AXES[i]), q[i]),
            );
            parent *= local;
            poses[i] = parent;
        }
        poses
    }

    /// Grasp point and tool frame for joint angles `q`: (grasp point, link-6 rotation).
    pub fn grasp_frame(q: &[f32; ARM_JOINTS]) -> (Vector, Rotation) {
        let last = Self::link_poses(q)[ARM_JOINTS - 1];
        let flange = last * (v(Self::FLANGE) - v(Self::JOINT_POINTS[ARM_JOINTS - 1]));
        let tool = last.rotation * v(Self::TOOL_AXIS);
        (flange + tool * GRASP_DEPTH, last.rotation)
    }
}

/// Array to vector.
pub fn v(a: [f32; 3]) -> Vector {
    Vector::new(a[0], a[1], a[2])
}
