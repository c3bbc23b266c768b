//! File names of the DMBN layout, in one place so the reader and writer cannot drift apart.
use std::path::{Path, PathBuf};

/// Frame sizes (pixels per side) the models work at and the simulator renders: the original
/// DMBN's two. The reader resizes to any size; these are the ones a network is defined for.
pub const IMAGE_SIZES: [usize; 2] = [64, 128];

/// The supported sizes as words, for error messages: "64 or 128".
pub fn image_sizes_text() -> String {
    IMAGE_SIZES.map(|s| s.to_string()).join(" or ")
}

/// Largest frame size (pixels per side) the reader resizes to; guards against typos that would
/// allocate gigabytes.
pub const MAX_IMAGE_SIZE: u32 = 4096;

/// `<dir>/joint_<id>.txt`: T rows of 7 joint values.
pub fn joint_path(dir: &Path, id: u32) -> PathBuf {
    dir.join(format!("joint_{id}.txt"))
}

/// `<dir>/object_<id>.txt`: T rows of object xyz.
pub fn object_path(dir: &Path, id: u32) -> PathBuf {
    dir.join(format!("object_{id}.txt"))
}

/// `<dir>/endpoint_<id>.txt`: T rows of end effector xyz, orientation, gripper.
pub fn endpoint_path(dir: &Path, id: u32) -> PathBuf {
    dir.join(format!("endpoint_{id}.txt"))
}

/// `<root>/<id>/<action>`: the folder of one sequence.
pub fn sequence_dir(root: &Path, id: u32, action: &str) -> PathBuf {
    root.join(id.to_string()).join(action)
}

/// True for a name usable as an action folder: non-empty, not hidden, no path separator.
pub(crate) fn valid_action_name(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && !name.contains(['/', '\\'])
        && !name.chars().any(char::is_control)
}
