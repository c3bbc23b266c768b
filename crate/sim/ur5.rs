use rapier3d::math::Vector;

use super::chain::{v, Chain, FINGER_OPEN};
use super::render::{Primitive, Shape};
use super::scene::{base_parts, capsule, cylinder, prim, BLUE, DARK, GRAY, WHITE};
use super::Arm;

/// UR5 Denavit-Hartenberg lengths (metres): shoulder height, upper arm, forearm, wrist offsets.
const D1: f32 = 0.089_159;
const A2: f32 = 0.425;
const A3: f32 = 0.392_25;
const D4: f32 = 0.109_15;
const D5: f32 = 0.094_65;
const D6: f32 = 0.0823;

/// The UR-like arm: the UR5 DH chain, base turned so the stretched arm points along +y; the
/// tool points along -x at q = 0, the fingers close along z. Joint limits are the UR's ±2π.
pub const UR5: Chain<6> = Chain {
    arm: Arm::Ur5,
    joint_points: [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, D1],
        [0.0, A2, D1],
        [0.0, A2 + A3, D1],
        [-D4, A2 + A3, D1],
        [-D4, A2 + A3, D1 - D5],
    ],
    joint_axes: [
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
        [-1.0, 0.0, 0.0],
    ],
    limits: [2.0 * core::f32::consts::PI; 6],
    masses: [2.0, 2.0, 2.0, 0.6, 0.6, 0.6],
    flange: [-D4 - D6, A2 + A3, D1 - D5],
    tool_axis: [-1.0, 0.0, 0.0],
    closing_axis: [0.0, 0.0, 1.0],
    finger_half: [0.035, 0.014, 0.008],
    home_guess: [0.0, -1.2, 1.5, -1.87, -core::f32::consts::FRAC_PI_2, 0.0],
    rest_gain: 0.0,
    link_parts,
};

/// The solids of link `i` (0 = base) at q = 0, in world coordinates: light tubes, dark
/// housings and blue joint caps, laid out like a UR5.
fn link_parts(i: usize) -> Vec<Primitive> {
    let p = |k: usize| v(UR5.joint_points[k]);
    let x = Vector::X;
    let z = Vector::Z;
    let (cyl, cap) = (cylinder, capsule);
    match i {
        0 => base_parts(),
        // Shoulder: vertical housing, cap on the lift axis.
        1 => vec![
            cyl(z * 0.07, p(1) + z * 0.02, 0.06, DARK),
            cyl(p(1) + x * 0.07, p(1) - x * 0.08, 0.062, BLUE),
        ],
        // Upper arm, offset along the lift axis like the UR5's.
        2 => {
            let off = -x * 0.135;
            vec![
                cyl(p(1) - x * 0.08, p(1) + off - x * 0.06, 0.06, DARK),
                cap(p(1) + off, p(2) + off, 0.045, GRAY),
                cyl(p(2) + off - x * 0.055, p(2) + off + x * 0.06, 0.058, BLUE),
            ]
        }
        // Forearm.
        3 => {
            let off = -x * 0.015;
            vec![
                cyl(p(2) - x * 0.075, p(2) + off + x * 0.045, 0.05, DARK),
                cap(p(2) + off, p(3) + off, 0.037, GRAY),
                cyl(p(3) + off + x * 0.05, p(3) - x * 0.07, 0.042, BLUE),
            ]
        }
        // Wrist 1: housing around the wrist-2 axis.
        4 => vec![
            cyl(p(3) - x * 0.07, p(4) + x * 0.01, 0.04, DARK),
            cyl(p(4) + z * 0.04, p(4) - z * 0.05, 0.042, BLUE),
        ],
        // Wrist 2: housing around the wrist-3 axis.
        5 => vec![
            cyl(p(4) - z * 0.05, p(5) - z * 0.0, 0.038, DARK),
            cyl(p(5) + x * 0.04, p(5) - x * 0.06, 0.04, BLUE),
        ],
        // Wrist 3: flange and gripper palm.
        _ => {
            let tool = v(UR5.tool_axis);
            let flange = v(UR5.flange);
            let half = Vector::new(0.02, 0.025, FINGER_OPEN + 0.012);
            vec![
                cyl(p(5) - x * 0.06, flange, 0.033, DARK),
                prim(
                    Shape::Cuboid {
                        center: flange + tool * 0.03,
                        rotation: rapier3d::math::Rotation::IDENTITY,
                        half,
                    },
                    WHITE,
                ),
            ]
        }
    }
}
