use super::chain::Chain;
use super::plan::Plan;
use super::render::Primitive;
use super::scene::{Scene, DT, SUBSTEPS};

/// One arm of `N` joints in its scene with the plan its motors track: what a
/// [`Simulator`](super::Simulator) drives, monomorphised per arm so that each arm's
/// arithmetic is fixed-size (and the UR5's is what it was before there were two arms).
pub(super) struct Rig<const N: usize> {
    plan: Plan<N>,
    scene: Scene<N>,
}

impl<const N: usize> Rig<N> {
    /// `chain`'s arm at `plan`'s first targets, the object at `object`.
    pub fn new(chain: &'static Chain<N>, plan: Plan<N>, object: [f32; 2]) -> Self {
        let scene = Scene::new(chain, &plan.joints[0], object);
        Rig { plan, scene }
    }

    /// Recorded steps of the plan.
    pub fn len(&self) -> usize {
        self.plan.len()
    }

    /// Track the plan from step `step` to the next over [`SUBSTEPS`] physics substeps: the
    /// targets move linearly, with the matching velocities.
    pub fn advance(&mut self, step: usize) {
        let (from, to) = (self.plan.joints[step], self.plan.joints[step + 1]);
        let (c0, c1) = (self.plan.closure[step], self.plan.closure[step + 1]);
        let span = SUBSTEPS as f32 * DT;
        let mut qdot = [0.0; N];
        for i in 0..N {
            qdot[i] = (to[i] - from[i]) / span;
        }
        for s in 1..=SUBSTEPS {
            let u = s as f32 / SUBSTEPS as f32;
            let mut q = [0.0; N];
            for i in 0..N {
                q[i] = from[i] + (to[i] - from[i]) * u;
            }
            self.scene.set_targets(&q, &qdot, c0 + (c1 - c0) * u);
            self.scene.step();
        }
    }

    /// Measured joint values: the angles (radians), then the gripper value.
    pub fn joints(&self) -> Vec<f32> {
        let mut row = self.scene.joint_angles().to_vec();
        row.push(self.scene.gripper());
        row
    }

    /// The scene, for its state and solids.
    pub fn scene(&self) -> &Scene<N> {
        &self.scene
    }

    /// Every solid in world coordinates, for the renderer.
    pub fn primitives(&self, out: &mut Vec<Primitive>) {
        self.scene.primitives(out);
    }
}
