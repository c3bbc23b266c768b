use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rapier3d::math::Vector;

use crate::data::{Sequence, IMAGE_SIZES};

use super::arm::ARM_JOINTS;
use super::plan::Plan;
use super::render::{Primitive, Renderer};
use super::scene::{Scene, CAMERA, DT, SUBSTEPS, TABLE};
use super::script::Script;
use super::{Action, SimError, Trajectory};

/// A running episode: physics scene, scripted plan and renderer.
///
/// Step 0 is the home pose; each [`step`](Simulator::step) advances the physics by
/// [`SUBSTEPS`] substeps while the motors track the plan, then the state can be read.
pub struct Simulator {
    plan: Plan,
    scene: Scene,
    renderer: Renderer,
    step: usize,
    primitives: Vec<Primitive>,
}

/// Seeds for the placement and the plan are drawn from separate streams, so an episode made
/// with `new(seed)` equals `with_object` at the position `new` drew, with the same seed.
const PLAN_STREAM: u64 = 0x9E37_79B9_7F4A_7C15;

impl Simulator {
    /// Region (metres, arm-base frame: x right, y away from the camera) where objects are placed.
    pub const REGION: ([f32; 2], [f32; 2]) = ([-0.15, 0.15], [0.45, 0.65]);

    /// An episode of `action` with the object placed from `seed`; frames `image_size` (64 or 128).
    pub fn new(action: Action, seed: u64, image_size: u32) -> Result<Self, SimError> {
        let [x, y] = Self::placement(seed);
        Self::with_object(action, x, y, seed, image_size)
    }

    /// Where `new(_, seed, _)` places the object (x, y on the table).
    pub fn placement(seed: u64) -> [f32; 2] {
        let mut rng = Pcg64::seed_from_u64(seed);
        let (rx, ry) = Self::REGION;
        let x = rng.random_range(rx[0]..=rx[1]);
        let y = rng.random_range(ry[0]..=ry[1]);
        [x, y]
    }

    /// An episode with the object at `(x, y)` on the table; `seed` still varies the timing
    /// and the free parameters of the script.
    pub fn with_object(
        action: Action,
        x: f32,
        y: f32,
        seed: u64,
        image_size: u32,
    ) -> Result<Self, SimError> {
        let (script, durations) = Self::script(action, [x, y], seed);
        Self::with_plan(script.plan(&durations), x, y, image_size)
    }

    /// The script and the segments' durations that `with_object(action, object, seed)`
    /// performs: the free parameters drawn first, then the durations.
    pub fn script(action: Action, object: [f32; 2], seed: u64) -> (Script, Vec<usize>) {
        let mut rng = Pcg64::seed_from_u64(seed ^ PLAN_STREAM);
        let script = Script::new(action, object, &mut rng);
        let durations = script.draw_durations(&mut rng);
        (script, durations)
    }

    /// The arm performing `trajectory` (see [`Plan::from_trajectory`]) with the object at
    /// `(x, y)`: the same motors, physics and recording as a scripted episode, one recorded
    /// step per row. The arm starts at the first row's angles.
    pub fn performing(
        trajectory: &Trajectory,
        x: f32,
        y: f32,
        image_size: u32,
    ) -> Result<Self, SimError> {
        Self::with_plan(Plan::from_trajectory(trajectory), x, y, image_size)
    }

    /// An episode whose motors track `plan`'s targets, with the object at `(x, y)`.
    pub fn with_plan(plan: Plan, x: f32, y: f32, image_size: u32) -> Result<Self, SimError> {
        if !IMAGE_SIZES.contains(&(image_size as usize)) {
            return Err(SimError::ImageSize(image_size));
        }
        let (rx, ry) = Self::REGION;
        if !(x >= rx[0] && x <= rx[1] && y >= ry[0] && y <= ry[1]) {
            return Err(SimError::ObjectOutOfRegion {
                x,
                y,
                x0: rx[0],
                x1: rx[1],
                y0: ry[0],
                y1: ry[1],
            });
        }
        let scene = Scene::new(&plan.joints[0], [x, y]);
        Ok(Simulator {
            plan,
            scene,
            renderer: Renderer::new(image_size, CAMERA, TABLE),
            step: 0,
            primitives: Vec::new(),
        })
    }

    /// Number of recorded steps the episode has.
    pub fn len(&self) -> usize {
        self.plan.len()
    }

    /// Always false: an episode has at least its home step.
    pub fn is_empty(&self) -> bool {
        self.plan.len() == 0
    }

    /// Index of the current step (0 after construction).
    pub fn step_index(&self) -> usize {
        self.step
    }

    /// Advance one recorded step; false (and no change) when the episode is over.
    pub fn step(&mut self) -> bool {
        if self.step + 1 >= self.plan.len() {
            return false;
        }
        let (from, to) = (self.plan.joints[self.step], self.plan.joints[self.step + 1]);
        let (c0, c1) = (
            self.plan.closure[self.step],
            self.plan.closure[self.step + 1],
        );
        let span = SUBSTEPS as f32 * DT;
        let mut qdot = [0.0; ARM_JOINTS];
        for i in 0..ARM_JOINTS {
            qdot[i] = (to[i] - from[i]) / span;
        }
        for s in 1..=SUBSTEPS {
            let u = s as f32 / SUBSTEPS as f32;
            let mut q = [0.0; ARM_JOINTS];
            for i in 0..ARM_JOINTS {
                q[i] = from[i] + (to[i] - from[i]) * u;
            }
            self.scene.set_targets(&q, &qdot, c0 + (c1 - c0) * u);
            self.scene.step();
        }
        self.step += 1;
        true
    }

    /// Joint values at the current step: 6 measured angles (radians), then the gripper value.
    pub fn joints(&self) -> [f32; 7] {
        let q = self.scene.joint_angles();
        [q[0], q[1], q[2], q[3], q[4], q[5], self.scene.gripper()]
    }

    /// End effector at the current step: grasp point xyz, orientation (XYZ Euler angles), gripper.
    pub fn endpoint(&self) -> [f32; 7] {
        let (p, rot) = self.scene.tcp();
        let (a, b, c) = rot.to_euler(rapier3d::glamx::EulerRot::XYZ);
        [p.x, p.y, p.z, a, b, c, self.scene.gripper()]
    }

    /// Object centre at the current step.
    pub fn object(&self) -> [f32; 3] {
        let p: Vector = self.scene.object_position();
        [p.x, p.y, p.z]
    }

    /// Frame size in pixels.
    pub fn image_size(&self) -> u32 {
        self.renderer.size()
    }

    /// Render the current step into `out` (`image_size² × 3` RGB bytes).
    pub fn render_into(&mut self, out: &mut [u8]) {
        self.scene.primitives(&mut self.primitives);
        self.renderer.render(&self.primitives, out);
    }

    /// RGB frame of the current step, `image_size² × 3` bytes.
    pub fn frame(&mut self) -> Vec<u8> {
        let n = self.image_size() as usize;
        let mut out = vec![0; n * n * 3];
        self.render_into(&mut out);
        out
    }

    /// Record the whole (remaining) episode, current step included.
    pub fn run(mut self) -> Sequence {
        let n = self.image_size() as usize;
        let steps = self.len() - self.step;
        let mut seq = Sequence {
            image_size: self.image_size(),
            joints: Vec::with_capacity(steps),
            endpoint: Vec::with_capacity(steps),
            object: Vec::with_capacity(steps),
            frames: vec![0; steps * n * n * 3],
        };
        let mut k = 0;
        loop {
            seq.joints.push(self.joints());
            seq.endpoint.push(self.endpoint());
            seq.object.push(self.object());
            let frame = &mut seq.frames[k * n * n * 3..(k + 1) * n * n * 3];
            self.scene.primitives(&mut self.primitives);
            self.renderer.render(&self.primitives, frame);
            k += 1;
            if !self.step() {
                break;
            }
        }
        seq
    }
}

/// Generate one whole episode.
pub fn episode(action: Action, seed: u64, image_size: u32) -> Result<Sequence, SimError> {
    Ok(Simulator::new(action, seed, image_size)?.run())
}

/// Record the arm performing `trajectory` with the object at `object` (x, y): see
/// [`Simulator::performing`].
pub fn perform(
    trajectory: &Trajectory,
    object: [f32; 2],
    image_size: u32,
) -> Result<Sequence, SimError> {
    Ok(Simulator::performing(trajectory, object[0], object[1], image_size)?.run())
}
