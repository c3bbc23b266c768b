use rapier3d::prelude::*;

use super::chain::{v, Chain, FINGER_OPEN, FINGER_TRAVEL};
use super::render::{Camera, Primitive, Shape, Table};

/// Object (a yellow cylinder) radius and half height, metres.
pub const OBJECT_RADIUS: f32 = 0.04;
pub const OBJECT_HALF_HEIGHT: f32 = 0.05;

/// Physics substeps per recorded step, and the substep length: frames are 20 per second.
pub const SUBSTEPS: usize = 3;
pub const DT: f32 = 1.0 / 60.0;

/// The table top seen by the camera (z = 0, arm base at the origin).
pub const TABLE: Table = Table {
    x: [-0.55, 0.55],
    y: [-0.12, 1.0],
    color: [0.17, 0.17, 0.17],
};
/// The fixed camera: behind and above the arm base, looking down the table.
pub const CAMERA: Camera = Camera {
    eye: Vector::new(0.0, -0.30, 1.50),
    target: Vector::new(0.0, 0.56, 0.0),
    fov_y: 0.70,
};

/// The arms' colours: light tubes, dark housings, blue caps, white gripper.
pub(super) const GRAY: [f32; 3] = [0.80, 0.80, 0.82];
pub(super) const DARK: [f32; 3] = [0.42, 0.42, 0.44];
pub(super) const BLUE: [f32; 3] = [0.42, 0.70, 0.95];
pub(super) const WHITE: [f32; 3] = [0.93, 0.93, 0.93];
const YELLOW: [f32; 3] = [0.96, 0.86, 0.02];

/// Collision groups: the arm and gripper touch only the object; the object touches everything.
const ARM: Group = Group::GROUP_1;
const OBJECT: Group = Group::GROUP_2;
const TABLE_GROUP: Group = Group::GROUP_3;

/// Motor gains (acceleration-based, so independent of link masses).
const ARM_STIFFNESS: f32 = 4000.0;
const ARM_DAMPING: f32 = 130.0;
const FINGER_STIFFNESS: f32 = 3000.0;
const FINGER_DAMPING: f32 = 110.0;
const FINGER_FORCE: f32 = 40.0;

/// A body of the scene with the solids drawn for it (in the body's frame).
#[derive(Debug, Clone)]
struct Visual {
    body: RigidBodyHandle,
    parts: Vec<Primitive>,
}

/// The physical world: table, object, and the arm as one rapier multibody (fixed base,
/// `N` revolute links, 2 prismatic fingers) driven by position motors.
pub struct Scene<const N: usize = 6> {
    chain: &'static Chain<N>,
    world: PhysicsWorld,
    joints: [MultibodyJointHandle; N],
    fingers: [MultibodyJointHandle; 2],
    tcp_link: RigidBodyHandle,
    object: RigidBodyHandle,
    visuals: Vec<Visual>,
}

impl<const N: usize> Scene<N> {
    /// Build the scene with `chain`'s arm at joint angles `q`, gripper open, object at `(x, y)`.
    pub fn new(chain: &'static Chain<N>, q: &[f32; N], object: [f32; 2]) -> Scene<N> {
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        world.integration_parameters.dt = DT;
        let mut visuals = Vec::new();

        // Table: a thick slab whose top is z = 0. The object slides on it with the table's
        // friction (the smaller of the two): with the average of the object's 1.2 and its 0.5
        // a push sat on the edge of tipping the cylinder over, and joints 0.002 rad off
        // toppled it in 8 pushes of 100 (measured; 0 of 100 at 0.01 rad with the table's).
        let table = world.bodies.insert(RigidBodyBuilder::fixed());
        let c = ColliderBuilder::cuboid(0.6, 0.7, 0.05)
            .translation(Vector::new(0.0, 0.45, -0.05))
            .friction(0.5)
            .friction_combine_rule(CoefficientCombineRule::Min)
            .collision_groups(InteractionGroups::new(
                TABLE_GROUP,
                OBJECT,
                InteractionTestMode::And,
            ));
        world
            .colliders
            .insert_with_parent(c, table, &mut world.bodies);

        // Object.
        let [ox, oy] = object;
        let body = world.bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(ox, oy, OBJECT_HALF_HEIGHT))
                .can_sleep(false),
        );
        let c = ColliderBuilder::cylinder(OBJECT_HALF_HEIGHT, OBJECT_RADIUS)
            .rotation(Vector::X * core::f32::consts::FRAC_PI_2)
            .density(350.0)
            .friction(1.2)
            .collision_groups(InteractionGroups::new(
                OBJECT,
                Group::ALL,
                InteractionTestMode::And,
            ));
        world
            .colliders
            .insert_with_parent(c, body, &mut world.bodies);
        let h = Vector::new(0.0, 0.0, OBJECT_HALF_HEIGHT);
        visuals.push(Visual {
            body,
            parts: vec![prim(
                Shape::Cylinder {
                    a: -h,
                    b: h,
                    radius: OBJECT_RADIUS,
                },
                YELLOW,
            )],
        });
        let object_body = body;

        // Arm: the base is the multibody's fixed root, every link starts world-aligned on its joint.
        let base = world.bodies.insert(RigidBodyBuilder::fixed());
        visuals.push(Visual {
            body: base,
            parts: (chain.link_parts)(0),
        });
        let mut parent = base;
        let mut joints = Vec::new();
        let mut tcp_link = base;
        for i in 0..N {
            let origin = v(chain.joint_points[i]);
            let link = insert_link(&mut world, origin, chain.masses[i], 0.01);
            let axis = v(chain.joint_axes[i]);
            let joint = RevoluteJointBuilder::new(axis)
                .local_anchor1(chain.anchor(i))
                .local_anchor2(Vector::ZERO)
                .motor_position(0.0, ARM_STIFFNESS, ARM_DAMPING)
                .motor_max_force(1.0e6)
                .contacts_enabled(false);
            let handle = world
                .multibody_joints
                .insert(parent, link, joint, true)
                .expect("a fresh multibody accepts every link");
            joints.push(handle);
            let parts = (chain.link_parts)(i + 1);
            for part in &parts {
                attach_collider(&mut world, link, &part.shape, origin, 0.8);
            }
            visuals.push(Visual {
                body: link,
                parts: shift(parts, origin),
            });
            parent = link;
            tcp_link = link;
        }

        // Fingers: prismatic children of the last link, sliding towards each other.
        let closing = v(chain.closing_axis);
        let tool = v(chain.tool_axis);
        let flange = v(chain.flange);
        let wrist = v(chain.joint_points[N - 1]);
        let mut fingers = Vec::new();
        for side in [1.0f32, -1.0] {
            let centre = flange + tool * 0.085 + closing * (side * FINGER_OPEN);
            let finger = insert_link(&mut world, centre, 0.3, 1e-3);
            let joint = PrismaticJointBuilder::new(closing * -side)
                .local_anchor1(centre - wrist)
                .local_anchor2(Vector::ZERO)
                .limits([0.0, FINGER_TRAVEL])
                .motor_position(0.0, FINGER_STIFFNESS, FINGER_DAMPING)
                .motor_max_force(FINGER_FORCE)
                .contacts_enabled(false);
            let handle = world
                .multibody_joints
                .insert(tcp_link, finger, joint, true)
                .expect("a fresh multibody accepts every finger");
            fingers.push(handle);
            let half = v(chain.finger_half);
            let shape = Shape::Cuboid {
                center: Vector::ZERO,
                rotation: rapier3d::math::Rotation::IDENTITY,
                half,
            };
            attach_collider(&mut world, finger, &shape, Vector::ZERO, 1.5);
            visuals.push(Visual {
                body: finger,
                parts: vec![prim(shape, WHITE)],
            });
        }

        let mut scene = Scene {
            chain,
            world,
            joints: joints.try_into().expect("a joint per link"),
            fingers: fingers.try_into().expect("two fingers"),
            tcp_link,
            object: object_body,
            visuals,
        };
        scene.set_configuration(q);
        scene
    }

    /// Teleport the arm to joint angles `q` (used once, to start at the home pose).
    fn set_configuration(&mut self, q: &[f32; N]) {
        let (mb, _) = self
            .world
            .multibody_joints
            .get(self.joints[0])
            .expect("arm joint");
        let mut disp = vec![0.0; mb.ndofs()];
        for (h, qi) in self.joints.iter().zip(q) {
            let (mb, id) = self.world.multibody_joints.get(*h).expect("arm joint");
            disp[mb.link(id).expect("arm link").assembly_id()] = *qi;
        }
        let (mb, _) = self
            .world
            .multibody_joints
            .get_mut(self.joints[0])
            .expect("arm joint");
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&self.world.bodies, true);
        mb.update_rigid_bodies(&mut self.world.bodies, true);
        self.set_targets(q, &[0.0; N], 0.0);
    }

    /// Motor targets: joint angles and velocities, and the gripper closure in [0, 1].
    pub fn set_targets(&mut self, q: &[f32; N], qdot: &[f32; N], closure: f32) {
        for i in 0..N {
            let (mb, id) = self
                .world
                .multibody_joints
                .get_mut(self.joints[i])
                .expect("arm joint");
            let joint = &mut mb.link_mut(id).expect("arm link").joint.data;
            joint.set_motor(JointAxis::AngX, q[i], qdot[i], ARM_STIFFNESS, ARM_DAMPING);
        }
        for h in self.fingers {
            let (mb, id) = self
                .world
                .multibody_joints
                .get_mut(h)
                .expect("finger joint");
            let joint = &mut mb.link_mut(id).expect("finger link").joint.data;
            joint.set_motor(
                JointAxis::LinX,
                closure * FINGER_TRAVEL,
                0.0,
                FINGER_STIFFNESS,
                FINGER_DAMPING,
            );
        }
    }

    /// Advance the physics by one substep.
    pub fn step(&mut self) {
        self.world.step();
    }

    /// Measured arm joint angles.
    pub fn joint_angles(&self) -> [f32; N] {
        let mut q = [0.0; N];
        for (qi, h) in q.iter_mut().zip(self.joints) {
            let (mb, id) = self.world.multibody_joints.get(h).expect("arm joint");
            *qi = mb.link(id).expect("arm link").joint.coords()[3];
        }
        q
    }

    /// Gripper value in the original's convention: 0 open, minus the total finger travel
    /// when closing (about -0.11 fully closed on nothing).
    pub fn gripper(&self) -> f32 {
        let mut travel = 0.0;
        for h in self.fingers {
            let (mb, id) = self.world.multibody_joints.get(h).expect("finger joint");
            travel += mb.link(id).expect("finger link").joint.coords()[0];
        }
        -travel
    }

    /// Grasp point position and last-link rotation, from the physics state.
    pub fn tcp(&self) -> (Vector, rapier3d::math::Rotation) {
        let pose = self.world.bodies[self.tcp_link].position();
        (pose * self.chain.grasp_offset(), pose.rotation)
    }

    /// Object centre.
    pub fn object_position(&self) -> Vector {
        self.world.bodies[self.object].translation()
    }

    /// Every solid in world coordinates, for the renderer.
    pub fn primitives(&self, out: &mut Vec<Primitive>) {
        out.clear();
        for vis in &self.visuals {
            let pose = self.world.bodies[vis.body].position();
            for p in &vis.parts {
                out.push(Primitive {
                    shape: p.shape.transformed(pose),
                    color: p.color,
                });
            }
        }
    }
}

/// A gravity-compensated multibody link at `origin` (world-aligned), with explicit mass
/// properties since its colliders have no density.
fn insert_link(
    world: &mut PhysicsWorld,
    origin: Vector,
    mass: f32,
    inertia: f32,
) -> RigidBodyHandle {
    world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(origin)
            .gravity_scale(0.0)
            .can_sleep(false)
            .additional_mass_properties(MassProperties::new(
                Vector::ZERO,
                mass,
                Vector::splat(inertia),
            )),
    )
}

pub(super) fn prim(shape: Shape, color: [f32; 3]) -> Primitive {
    Primitive { shape, color }
}

/// A cylinder from `a` to `b`: the arms' tubes and housings.
pub(super) fn cylinder(a: Vector, b: Vector, radius: f32, color: [f32; 3]) -> Primitive {
    prim(Shape::Cylinder { a, b, radius }, color)
}

/// A capsule from `a` to `b`.
pub(super) fn capsule(a: Vector, b: Vector, radius: f32, color: [f32; 3]) -> Primitive {
    prim(Shape::Capsule { a, b, radius }, color)
}

/// The base both arms stand on: a blue plinth and a dark ring.
pub(super) fn base_parts() -> Vec<Primitive> {
    let z = Vector::Z;
    vec![
        cylinder(Vector::ZERO, z * 0.055, 0.075, BLUE),
        cylinder(z * 0.055, z * 0.07, 0.062, DARK),
    ]
}

/// Move parts given in world coordinates at q = 0 into the frame of a body whose origin is `origin`.
fn shift(parts: Vec<Primitive>, origin: Vector) -> Vec<Primitive> {
    let pose = rapier3d::math::Pose::from_translation(-origin);
    parts
        .into_iter()
        .map(|p| prim(p.shape.transformed(&pose), p.color))
        .collect()
}

/// A collider matching a solid (capsule for round parts, cuboid for boxes), in the body frame.
fn attach_collider(
    world: &mut PhysicsWorld,
    body: RigidBodyHandle,
    shape: &Shape,
    origin: Vector,
    friction: f32,
) {
    let builder = match *shape {
        Shape::Cylinder { a, b, radius } | Shape::Capsule { a, b, radius } => {
            ColliderBuilder::capsule_from_endpoints(a - origin, b - origin, radius)
        }
        Shape::Cuboid {
            center,
            rotation,
            half,
        } => ColliderBuilder::cuboid(half.x, half.y, half.z)
            .position(rapier3d::math::Pose::from_parts(center - origin, rotation)),
    };
    let c = builder
        .density(0.0)
        .friction(friction)
        .collision_groups(InteractionGroups::new(
            ARM,
            OBJECT,
            InteractionTestMode::And,
        ));
    world
        .colliders
        .insert_with_parent(c, body, &mut world.bodies);
}
