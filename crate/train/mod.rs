//! Training (native only): batched context/target sampling, Adam with gradient clipping and a
//! learning-rate schedule, a held-out validation split, JSON-lines metrics, and atomic
//! checkpoints that `--resume` continues exactly; on one device or, the batch split, several;
//! the training frames read from disk as the batches need them.
mod add_joint_stage;
mod batch_stream;
mod checkpoint;
mod config;
mod data_parallel;
mod error;
mod frame_cache;
mod joint_stage_examples;
mod joint_stage_fit;
mod metrics;
mod sequence_store;
mod split;
mod train_device;
mod train_devices;
mod trainer;
mod val_quality;

use batch_stream::BatchStream;
use frame_cache::FrameCache;
use sequence_store::SequenceStore;

pub use add_joint_stage::{add_joint_stage, JointStageProgress};
pub use checkpoint::{Checkpoint, CheckpointState};
pub use config::{Schedule, TrainConfig};
pub use error::TrainError;
pub use joint_stage_examples::{layout, JointStageExamples};
pub use joint_stage_fit::{fit_joint_stage, JointStageFit, JointStageFitProgress};
pub use metrics::{Metrics, MetricsLog};
pub use split::Split;
pub use train_device::TrainDevice;
pub use train_devices::TrainDevices;
pub use trainer::{Progress, Trainer};
pub use val_quality::ValQuality;
