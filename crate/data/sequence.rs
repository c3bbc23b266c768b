use sha2::{Digest, Sha256};

use super::Joints;

/// Joint values per step of the original DMBN arm and of the simulator's UR5-like arm: 6 arm
/// angles (radians), then the gripper. Other robots bring their own count ([`Joints::width`]).
pub const JOINTS: usize = 7;
/// Number of end-effector values per step: position xyz, orientation (3 Euler angles), gripper.
pub const ENDPOINT: usize = 7;

/// One recorded action: per step the joint values, end-effector pose, object position and an
/// RGB frame. This is the unit everything downstream (augmentation, models) consumes, whether
/// it came from our simulator or from the original DMBN dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    /// Width and height of every frame, in pixels.
    pub image_size: u32,
    /// `[T][D]`: the robot's joint values (the original's: 6 angles in radians, then the
    /// gripper, 0 open, negative closing). By convention the last of several is the gripper.
    pub joints: Joints,
    /// `[T][7]`: end effector xyz, 3 orientation values, gripper (the original's column
    /// meaning); `None` where the data has no `endpoint_<id>.txt` (most robots record none).
    pub endpoint: Option<Vec<[f32; ENDPOINT]>>,
    /// `[T][3]`: object position xyz; `None` where the data has no `object_<id>.txt`.
    pub object: Option<Vec<[f32; 3]>>,
    /// `T * image_size * image_size * 3` bytes: frames in step order, rows top to bottom, RGB.
    pub frames: Vec<u8>,
}

impl Sequence {
    /// Number of steps.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// True when the sequence has no step.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Bytes in one frame.
    pub fn frame_bytes(&self) -> usize {
        (self.image_size * self.image_size * 3) as usize
    }

    /// The RGB bytes of frame `k`.
    pub fn frame(&self, k: usize) -> &[u8] {
        let n = self.frame_bytes();
        &self.frames[k * n..(k + 1) * n]
    }

    /// Phase of each step, `linspace(0, 1, T)`: the time the models see.
    pub fn times(&self) -> Vec<f32> {
        let t = self.len();
        (0..t).map(|k| Sequence::phase(k, t)).collect()
    }

    /// The phase of step `k` of a `t`-step sequence (see [`Sequence::times`]): the sampler
    /// times steps of sequences whose frames it has not read.
    pub fn phase(k: usize, t: usize) -> f32 {
        if t > 1 {
            k as f32 / (t - 1) as f32
        } else {
            0.0
        }
    }

    /// SHA-256 (hex) of the joints, endpoint, object (f32 little-endian bits) and frame bytes:
    /// the fingerprint that native and wasm runs are checked against.
    pub fn digest(&self) -> String {
        let mut h = Sha256::new();
        h.update(self.image_size.to_le_bytes());
        h.update((self.len() as u64).to_le_bytes());
        for v in self.joints.values() {
            h.update(v.to_le_bytes());
        }
        for v in self.endpoint.iter().flatten().flatten() {
            h.update(v.to_le_bytes());
        }
        for v in self.object.iter().flatten().flatten() {
            h.update(v.to_le_bytes());
        }
        h.update(&self.frames);
        h.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }
}
