//! Sequences and datasets in the original DMBN folder layout:
//!
//! ```text
//! <root>/dataset.json                       optional: joint_names, cameras, fps, source
//! <root>/<id>/<action>/<k>.png (or .jpeg)   frames 0..T-1 of the default camera, any size
//! <root>/<id>/<action>/<camera>/<k>.png     frames of another camera (optional, any number)
//! <root>/<id>/<action>/joint_<id>.txt       T rows x D: the robot's joint values (the
//!                                           original's D = 7: 6 joint angles, gripper)
//! <root>/<id>/<action>/object_<id>.txt      optional, T rows x 3: object xyz
//! <root>/<id>/<action>/endpoint_<id>.txt    optional, T rows x 7: end effector pose, gripper
//! ```
//!
//! D comes from the data: every joint file of a dataset must have as many values a step
//! ([`Dataset::check_width`]), and a model is trained for one D (its file says which).
//!
//! Reading validates everything (column counts, numbers, row counts, frame count and size)
//! and reports the offending file; writing is atomic per file, and [`DatasetWriter`] builds a
//! whole dataset in a temporary folder renamed into place at the end. Action folders are plain
//! names here (`"grasp"`, `"move"`) so this module does not depend on the simulator. The files
//! are read through [`Files`]: from the disk ([`Disk`]) or from memory ([`MemoryFiles`], the
//! page's chosen folder), with the same rules and messages.
mod action_summary;
mod atomic_write;
mod dataset;
mod dataset_meta;
mod dataset_writer;
mod error;
mod files;
mod ids;
mod joint_scale;
mod joints;
mod layout;
mod memory_files;
mod normalization;
mod reader;
mod sequence;
mod sequence_ref;
mod sequence_writer;
mod summary;

pub use action_summary::ActionSummary;
pub use atomic_write::write_atomic;
pub use dataset::Dataset;
pub use dataset_meta::DatasetMeta;
pub use dataset_writer::DatasetWriter;
pub use error::DataError;
pub use files::{Disk, Files};
pub use ids::id_list;
pub use joint_scale::JointScale;
pub use joints::{arm_joints, Joints};
pub use layout::{
    endpoint_path, image_sizes_text, joint_path, object_path, sequence_dir, IMAGE_SIZES,
    MAX_IMAGE_SIZE,
};
pub use memory_files::MemoryFiles;
pub use normalization::Normalization;
pub use reader::{camera_dir, read_frames, read_joints, read_sequence, read_sequence_from};
pub use sequence::{Sequence, ENDPOINT, JOINTS};
pub use sequence_ref::SequenceRef;
pub use sequence_writer::write_sequence;
pub use summary::Summary;
