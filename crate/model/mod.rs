//! DMBN, DMBN-PTE and the attentive model in burn, following the paper's Figure 1: context inputs → encoders
//! ([`ImageEncoder`], [`JointEncoder`]; for DMBN-PTE plus [`TimeProjection`] and
//! [`ContextProjection`]) → set average and blending ([`masked_mean`], [`blend`]) → target
//! time → [`Decoder`] ([`ImageDecoder`], [`JointDecoder`]) → mean and σ ([`Prediction`]),
//! scored by [`gaussian_loss`]. [`Model`] wraps either network with its [`ModelConfig`], and
//! [`file`](mod@file) stores it with its [`Normalization`] in one self-describing file.
//!
//! Nothing here knows about datasets or files on disk beyond the model file; a [`Batch`]
//! (plain arrays from the sampler) becomes [`BatchTensors`] through [`tensors`].
//!
//! [`Batch`]: crate::augment::Batch
mod aggregation;
mod batch_tensors;
mod config;
mod context_projection;
#[cfg(not(target_arch = "wasm32"))]
mod conv_op;
mod decoder;
mod dmbn;
mod dmbn_attn;
mod dmbn_pte;
mod encoded_contexts;
mod error;
pub mod file;
mod gaussian;
mod image_decoder;
mod image_encoder;
mod init;
mod interpolation;
mod joint_correlation;
mod joint_decoder;
mod joint_encoder;
mod joint_sigma_scale;
mod joint_stage;
mod joint_stage_inputs;
pub mod k_means;
mod kernels;
mod latent_path;
mod loss;
mod maps;
#[allow(clippy::module_inception)]
mod model;
mod prediction;
#[cfg(not(target_arch = "wasm32"))]
pub mod safetensors_file;
mod start;
#[cfg(test)]
mod testing;
mod time_embedding;
mod time_projection;
mod values;

pub use crate::data::Normalization;
pub use aggregation::{blend, masked_mean};
pub use batch_tensors::{joint_target_tensors, tensors, BatchTensors};
pub use config::{decoder_filters, encoder_filters, ModelConfig, ModelKind, IMAGE_SIZES};
pub use context_projection::{ContextProjection, ContextProjectionConfig};
pub use decoder::{Decoder, DecoderConfig};
pub use dmbn::Dmbn;
pub use dmbn_attn::DmbnAttn;
pub use dmbn_pte::DmbnPte;
pub use encoded_contexts::EncodedContexts;
pub use error::ModelError;
pub use file::{
    load_bytes, load_bytes_expecting, load_with_header, read_header, save_bytes,
    with_joint_correlation, with_joint_sigma_scale, ModelHeader, WeightDType,
};
pub use gaussian::bounded_sigma;
pub use image_decoder::{upsample2, DecodedFrames, ImageDecoder, ImageDecoderConfig};
pub use image_encoder::{ImageEncoder, ImageEncoderConfig};
pub use init::{glorot, Initialization};
pub use interpolation::{gaps, interpolation_tensors, linear_weights};
pub use joint_correlation::JointCorrelation;
pub use joint_decoder::{JointDecoder, JointDecoderConfig};
pub use joint_encoder::{JointEncoder, JointEncoderConfig};
pub use joint_sigma_scale::JointSigmaScale;
pub use joint_stage::{JointStage, JointStageConfig, JOINT_STAGE_LAYERS, JOINT_STAGE_SIGMA_FLOOR};
pub use joint_stage_inputs::{
    joint_stage_input_len, joint_stage_inputs, JOINT_STAGE_FREQUENCIES, JOINT_STAGE_SLOTS,
};
pub use latent_path::{kl_divergence, LatentGaussian, LatentPath, LatentPathConfig};
pub use loss::{gaussian_loss, joint_nll, Loss, LossValues};
pub use model::{Model, Network};
pub use prediction::{AttentiveContexts, ContextEncodings, Prediction, Representation};
#[cfg(not(target_arch = "wasm32"))]
pub use safetensors_file::{
    export_file, export_safetensors, import_file, import_safetensors, SafetensorsHeader,
};
pub use start::{FrameStart, JointStart, Start};
pub use time_embedding::{TimeEmbedding, TimeEmbeddingConfig};
pub use time_projection::{TimeProjection, TimeProjectionConfig};
pub use values::values;
