use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rapier3d::math::Vector;

use crate::data::{Joints, Sequence, IMAGE_SIZES};

use super::panda::PANDA;
use super::plan::Plan;
use super::render::{Primitive, Renderer};
use super::rig::Rig;
#[cfg(doc)]
use super::scene::SUBSTEPS;
use super::scene::{CAMERA, TABLE};
use super::script::Script;
use super::ur5::UR5;
use super::{Action, Arm, SimError, Trajectory};

/// A running episode: physics scene, scripted plan and renderer, for one of the [`Arm`]s.
///
/// Step 0 is the home pose; each [`step`](Simulator::step) advances the physics by
/// [`SUBSTEPS`] substeps while the motors track the plan, then the state can be read.
pub struct Simulator {
    rig: AnyRig,
    renderer: Renderer,
    step: usize,
    primitives: Vec<Primitive>,
}

/// The arm of an episode, each with its own joint count.
enum AnyRig {
    Ur5(Rig<6>),
    Panda(Rig<7>),
}

/// `$body` with `$rig` bound to whichever arm's [`Rig`] `$any` holds.
macro_rules! on_rig {
    ($any:expr, $rig:ident => $body:expr) => {
        match $any {
            AnyRig::Ur5($rig) => $body,
            AnyRig::Panda($rig) => $body,
        }
    };
}

/// Seeds for the placement and the plan are drawn from separate streams, so an episode made
/// with `new(seed)` equals `with_object` at the position `new` drew, with the same seed.
const PLAN_STREAM: u64 = 0x9E37_79B9_7F4A_7C15;

impl Simulator {
    /// Region (metres, arm-base frame: x right, y away from the camera) where objects are placed.
    pub const REGION: ([f32; 2], [f32; 2]) = ([-0.15, 0.15], [0.45, 0.65]);

    /// A UR5 episode of `action` with the object placed from `seed`; frames `image_size`
    /// (64 or 128).
    pub fn new(action: Action, seed: u64, image_size: u32) -> Result<Self, SimError> {
        Self::new_with_arm(Arm::Ur5, action, seed, image_size)
    }

    /// `arm`'s episode of `action` with the object placed from `seed` (where either arm
    /// finds it, and with the same script: the arms differ only in the joints that realise
    /// the gripper's poses).
    pub fn new_with_arm(
        arm: Arm,
        action: Action,
        seed: u64,
        image_size: u32,
    ) -> Result<Self, SimError> {
        let [x, y] = Self::placement(seed);
        Self::with_object_on(arm, action, x, y, seed, image_size)
    }

    /// Where `new(_, seed, _)` places the object (x, y on the table).
    pub fn placement(seed: u64) -> [f32; 2] {
        let mut rng = Pcg64::seed_from_u64(seed);
        let (rx, ry) = Self::REGION;
        let x = rng.random_range(rx[0]..=rx[1]);
        let y = rng.random_range(ry[0]..=ry[1]);
        [x, y]
    }

    /// A UR5 episode with the object at `(x, y)` on the table; `seed` still varies the
    /// timing and the free parameters of the script.
    pub fn with_object(
        action: Action,
        x: f32,
        y: f32,
        seed: u64,
        image_size: u32,
    ) -> Result<Self, SimError> {
        Self::with_object_on(Arm::Ur5, action, x, y, seed, image_size)
    }

    /// `arm`'s episode with the object at `(x, y)` (see [`Simulator::with_object`]).
    pub fn with_object_on(
        arm: Arm,
        action: Action,
        x: f32,
        y: f32,
        seed: u64,
        image_size: u32,
    ) -> Result<Self, SimError> {
        let (script, durations) = Self::script(action, [x, y], seed);
        match arm {
            Arm::Ur5 => Self::with_plan(script.plan(&durations), x, y, image_size),
            Arm::Panda => {
                Self::with_panda_plan(script.plan_on(&PANDA, &durations), x, y, image_size)
            }
        }
    }

    /// The script and the segments' durations that `with_object(action, object, seed)`
    /// performs: the free parameters drawn first, then the durations.
    pub fn script(action: Action, object: [f32; 2], seed: u64) -> (Script, Vec<usize>) {
        let mut rng = Pcg64::seed_from_u64(seed ^ PLAN_STREAM);
        let script = Script::new(action, object, &mut rng);
        let durations = script.draw_durations(&mut rng);
        (script, durations)
    }

    /// The trajectory's arm performing it (see [`Plan::from_trajectory`]) with the object at
    /// `(x, y)`: the same motors, physics and recording as a scripted episode, one recorded
    /// step per row. The arm starts at the first row's angles.
    pub fn performing(
        trajectory: &Trajectory,
        x: f32,
        y: f32,
        image_size: u32,
    ) -> Result<Self, SimError> {
        match trajectory.arm() {
            Arm::Ur5 => Self::with_plan(Plan::from_trajectory(trajectory), x, y, image_size),
            Arm::Panda => {
                Self::with_panda_plan(Plan::from_trajectory(trajectory), x, y, image_size)
            }
        }
    }

    /// A UR5 episode whose motors track `plan`'s targets, with the object at `(x, y)`.
    pub fn with_plan(plan: Plan, x: f32, y: f32, image_size: u32) -> Result<Self, SimError> {
        Self::check(x, y, image_size)?;
        Ok(Self::with_rig(
            AnyRig::Ur5(Rig::new(&UR5, plan, [x, y])),
            image_size,
        ))
    }

    /// A Panda episode whose motors track `plan`'s targets, with the object at `(x, y)`.
    pub fn with_panda_plan(
        plan: Plan<7>,
        x: f32,
        y: f32,
        image_size: u32,
    ) -> Result<Self, SimError> {
        Self::check(x, y, image_size)?;
        Ok(Self::with_rig(
            AnyRig::Panda(Rig::new(&PANDA, plan, [x, y])),
            image_size,
        ))
    }

    fn with_rig(rig: AnyRig, image_size: u32) -> Self {
        Simulator {
            rig,
            renderer: Renderer::new(image_size, CAMERA, TABLE),
            step: 0,
            primitives: Vec::new(),
        }
    }

    /// Fails unless frames of `image_size` are made and `(x, y)` lies in the region.
    fn check(x: f32, y: f32, image_size: u32) -> Result<(), SimError> {
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
        Ok(())
    }

    /// The arm performing.
    pub fn arm(&self) -> Arm {
        match self.rig {
            AnyRig::Ur5(_) => Arm::Ur5,
            AnyRig::Panda(_) => Arm::Panda,
        }
    }

    /// Number of recorded steps the episode has.
    pub fn len(&self) -> usize {
        on_rig!(&self.rig, rig => rig.len())
    }

    /// Always false: an episode has at least its home step.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the current step (0 after construction).
    pub fn step_index(&self) -> usize {
        self.step
    }

    /// Advance one recorded step; false (and no change) when the episode is over.
    pub fn step(&mut self) -> bool {
        if self.step + 1 >= self.len() {
            return false;
        }
        on_rig!(&mut self.rig, rig => rig.advance(self.step));
        self.step += 1;
        true
    }

    /// Joint values at the current step: the arm's measured angles (radians; 6 for the
    /// UR5, 7 for the Panda), then the gripper value.
    pub fn joints(&self) -> Vec<f32> {
        on_rig!(&self.rig, rig => rig.joints())
    }

    /// End effector at the current step: grasp point xyz, orientation (XYZ Euler angles of
    /// the last link), gripper.
    pub fn endpoint(&self) -> [f32; 7] {
        let ((p, rot), gripper) =
            on_rig!(&self.rig, rig => (rig.scene().tcp(), rig.scene().gripper()));
        let (a, b, c) = rot.to_euler(rapier3d::glamx::EulerRot::XYZ);
        [p.x, p.y, p.z, a, b, c, gripper]
    }

    /// Object centre at the current step.
    pub fn object(&self) -> [f32; 3] {
        let p: Vector = on_rig!(&self.rig, rig => rig.scene().object_position());
        [p.x, p.y, p.z]
    }

    /// Frame size in pixels.
    pub fn image_size(&self) -> u32 {
        self.renderer.size()
    }

    /// Render the current step into `out` (`image_size² × 3` RGB bytes).
    pub fn render_into(&mut self, out: &mut [u8]) {
        on_rig!(&self.rig, rig => rig.primitives(&mut self.primitives));
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
        let mut joints = Joints::with_width(self.arm().width());
        let mut endpoint = Vec::with_capacity(steps);
        let mut object = Vec::with_capacity(steps);
        let mut frames = vec![0; steps * n * n * 3];
        let mut k = 0;
        loop {
            joints.push(&self.joints());
            endpoint.push(self.endpoint());
            object.push(self.object());
            let frame = &mut frames[k * n * n * 3..(k + 1) * n * n * 3];
            self.render_into(frame);
            k += 1;
            if !self.step() {
                break;
            }
        }
        Sequence {
            image_size: self.image_size(),
            joints,
            endpoint: Some(endpoint),
            object: Some(object),
            frames,
        }
    }
}

/// Generate one whole UR5 episode.
pub fn episode(action: Action, seed: u64, image_size: u32) -> Result<Sequence, SimError> {
    episode_with_arm(Arm::Ur5, action, seed, image_size)
}

/// Generate one whole episode of `arm`.
pub fn episode_with_arm(
    arm: Arm,
    action: Action,
    seed: u64,
    image_size: u32,
) -> Result<Sequence, SimError> {
    Ok(Simulator::new_with_arm(arm, action, seed, image_size)?.run())
}

/// Record the trajectory's arm performing it with the object at `object` (x, y): see
/// [`Simulator::performing`].
pub fn perform(
    trajectory: &Trajectory,
    object: [f32; 2],
    image_size: u32,
) -> Result<Sequence, SimError> {
    Ok(Simulator::performing(trajectory, object[0], object[1], image_size)?.run())
}
