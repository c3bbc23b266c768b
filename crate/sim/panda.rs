use rapier3d::math::Vector;

use super::chain::{v, Chain, FINGER_OPEN};
use super::render::{Primitive, Shape};
use super::scene::{base_parts, capsule, cylinder, prim, DARK, GRAY, WHITE};
use super::Arm;

/// Franka Panda lengths (metres): shoulder height, upper arm, elbow offset, forearm, wrist
/// offset, flange.
const D1: f32 = 0.333;
const D3: f32 = 0.316;
const A4: f32 = 0.0825;
const D5: f32 = 0.384;
const A7: f32 = 0.088;
const DF: f32 = 0.107;

/// The Panda-like arm: the Panda's chain (shoulder, elbow and wrist each a pitch between two
/// rolls, so one joint is redundant) stretched up at q = 0 with its elbow offset towards the
/// table (+y) and the flange hanging down from the wrist; the fingers close along x. Its
/// limits are the Panda's widest, taken symmetric. The base sits where the UR5's does.
pub const PANDA: Chain<7> = Chain {
    arm: Arm::Panda,
    joint_points: [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, D1],
        [0.0, 0.0, D1 + D3],
        [0.0, A4, D1 + D3],
        [0.0, 0.0, D1 + D3 + D5],
        [0.0, 0.0, D1 + D3 + D5],
        [0.0, A7, D1 + D3 + D5],
    ],
    joint_axes: [
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0],
    ],
    limits: [2.8973, 1.7628, 2.8973, 3.0718, 2.8973, 3.7525, 2.8973],
    masses: [2.0, 2.0, 2.0, 1.2, 0.6, 0.6, 0.6],
    flange: [0.0, A7, D1 + D3 + D5 - DF],
    tool_axis: [0.0, 0.0, -1.0],
    closing_axis: [1.0, 0.0, 0.0],
    finger_half: [0.008, 0.014, 0.035],
    // Upper arm nearly upright, elbow high, forearm reaching down to the table, hand level.
    home_guess: [0.0, -0.13, 0.0, 2.03, 0.0, -1.9, 0.0],
    rest_gain: 0.1,
    link_parts,
};

/// The solids of link `i` (0 = base) at q = 0, in world coordinates: light tubes, dark joint
/// housings, laid out like a Panda.
fn link_parts(i: usize) -> Vec<Primitive> {
    let p = |k: usize| v(PANDA.joint_points[k]);
    let x = Vector::X;
    let z = Vector::Z;
    let (cyl, cap) = (cylinder, capsule);
    match i {
        0 => base_parts(),
        // Shoulder: upright column, housing on the pitch axis.
        1 => vec![
            cap(z * 0.07, p(1) - z * 0.03, 0.055, GRAY),
            cyl(p(1) + x * 0.065, p(1) - x * 0.065, 0.06, DARK),
        ],
        // Upper arm, lower half (rolls with joint 3 above it).
        2 => vec![cap(p(1), p(1) + z * 0.2, 0.05, GRAY)],
        // Upper arm, upper half, and the bracket out to the elbow.
        3 => vec![
            cap(p(1) + z * 0.2, p(2), 0.05, GRAY),
            cap(p(2), p(3), 0.045, GRAY),
        ],
        // Elbow housing and forearm, back over the arm's line.
        4 => {
            let bend = p(3) + z * 0.1;
            vec![
                cyl(p(3) + x * 0.06, p(3) - x * 0.06, 0.055, DARK),
                cap(p(3), bend, 0.045, GRAY),
                cap(bend, p(4) - z * 0.12, 0.042, GRAY),
            ]
        }
        // Forearm top (rolls with joint 5), wrist housing on the pitch axis.
        5 => vec![
            cap(p(4) - z * 0.12, p(5), 0.042, GRAY),
            cyl(p(5) + x * 0.055, p(5) - x * 0.055, 0.05, DARK),
        ],
        // Wrist: out to the flange roll, its housing hanging down.
        6 => vec![
            cap(p(5), p(6), 0.04, GRAY),
            cyl(p(6) + z * 0.03, p(6) - z * 0.05, 0.045, DARK),
        ],
        // Flange roll and gripper palm.
        _ => {
            let tool = v(PANDA.tool_axis);
            let flange = v(PANDA.flange);
            let half = Vector::new(FINGER_OPEN + 0.012, 0.025, 0.02);
            vec![
                cyl(p(6) - z * 0.05, flange, 0.033, DARK),
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
