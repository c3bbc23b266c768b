use burn::config::Config;
use serde::{Deserialize, Serialize};

use super::image_decoder::IMAGE_DECODER_TAIL;
use super::ModelError;

pub use crate::data::IMAGE_SIZES;

/// Which network: the paper's two, or the attentive model (named `dmbn`, `pte` or `attn` in
/// model files and on the command line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// The original DMBN, "time as channel": the context time is an input channel of both
    /// encoders and the target time is concatenated to the representation.
    Dmbn,
    /// DMBN-PTE, "time as context" (positional time encoding): a shared projection P(t) is
    /// added to every context encoding and subtracted from the representation per target.
    Pte,
    /// The attentive model: DMBN-PTE's context encodings aggregated per target by
    /// cross-attention over the context times instead of a mean.
    Attn,
}

impl ModelKind {
    /// Every kind.
    pub const ALL: [ModelKind; 3] = [ModelKind::Dmbn, ModelKind::Pte, ModelKind::Attn];

    /// The name used in model files and on the command line: `dmbn`, `pte` or `attn`.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Dmbn => "dmbn",
            ModelKind::Pte => "pte",
            ModelKind::Attn => "attn",
        }
    }
}

impl std::fmt::Display for ModelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ModelKind {
    type Err = ModelError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "dmbn" => Ok(ModelKind::Dmbn),
            "pte" | "dmbn-pte" => Ok(ModelKind::Pte),
            "attn" => Ok(ModelKind::Attn),
            _ => Err(ModelError::config(
                "kind",
                format!("is {s:?}: expected \"dmbn\", \"pte\" or \"attn\""),
            )),
        }
    }
}

/// The largest latent z ([`ModelConfig::latent`]).
pub const MAX_LATENT: usize = 256;

/// Everything that defines a model besides its weights; saved in the model file's header.
#[derive(Config, Debug, PartialEq)]
pub struct ModelConfig {
    /// Which network: DMBN, DMBN-PTE or the attentive model.
    pub kind: ModelKind,
    /// Frame width and height: 64 or 128.
    #[config(default = 64)]
    pub image_size: usize,
    /// Size of the context encodings and of the representation (H).
    #[config(default = 128)]
    pub hidden: usize,
    /// Lower bound of every predicted σ: σ = floor + (1 − floor)·softplus(raw), in [0, 1).
    #[config(default = 0.01)]
    pub sigma_floor: f64,
    /// Weight of the joint NLL in the total loss (the image NLL has weight 1).
    #[config(default = 0.01)]
    pub joint_weight: f64,
    /// Attention heads of the attentive model (a divisor of `hidden`); unused by the others.
    /// Absent from files written before the attentive model: those hold no such model.
    pub heads: Option<usize>,
    /// Filters of every image-decoder convolution before the heads: one per upsampling
    /// block, then the two at full resolution. Absent: the original's (see
    /// [`ModelConfig::image_decoder`]); a narrower decoder decodes a frame with fewer
    /// multiply-adds (the page's live mode).
    pub decoder_filters: Option<Vec<usize>>,
    /// `Some(true)`: the image decoder's two tail convolutions run at half resolution, before
    /// the last upsampling, and only the heads at full resolution (9.8 M multiply-adds a 64x64
    /// frame instead of 16 M at the half-width filters). Absent (older files) or false: the original's.
    pub coarse_tail: Option<bool>,
    /// Filters of the image encoder's conv blocks, one per block. Absent: the original's (see
    /// [`encoder_filters`]); a narrower encoder encodes an observation with fewer
    /// multiply-adds (live mode encodes each new one before it forecasts).
    pub encoder_filters: Option<Vec<usize>>,
    /// The attentive model: `Some(true)` reads the joints from each observed frame (a linear
    /// head on its image context encoding), and where joints are not observed (frames only)
    /// the joint decoder starts from those, interpolated as observed joints would be, instead
    /// of from nothing. Absent (older files) or false: it starts from nothing.
    pub frame_joints: Option<bool>,
    /// Width of the joint stage ([`super::JointStage`]): the file holds one, which gives the
    /// joints wherever the observations are frames only (blend 1). Absent (older files, or
    /// none fitted): the network's own joints. Named `mirror`, the stage's old name, because
    /// the field's name is its key in model files (burn's `Config` derive takes no serde
    /// rename).
    pub mirror: Option<usize>,
    /// The attentive model: size L of a global latent z ([`super::LatentPath`]), drawn once
    /// per sampled future. Absent (older files): none; futures are drawn autoregressively.
    pub latent: Option<usize>,
    /// Joint values a step (D), read from the training data: sizes the joint encoder, the
    /// joint decoder's heads, the attentive model's read-out and the joint stage. Absent
    /// (files written before other robots): 7, the original arm's.
    pub joints: Option<usize>,
    /// A name for each joint value (from the dataset's `dataset.json`); absent where the data
    /// named none.
    pub joint_names: Option<Vec<String>>,
}

impl ModelConfig {
    /// Checks every field: a supported image size, a non-zero hidden size, a σ floor in
    /// [0, 1) and a finite, non-negative joint weight.
    pub fn validate(&self) -> Result<(), ModelError> {
        self.image_encoder()?;
        if self.joints == Some(0) {
            return Err(ModelError::config(
                "joints",
                "is 0: expected the number of joint values a step (at least 1)",
            ));
        }
        if let Some(names) = &self.joint_names {
            if names.len() != self.joint_count() {
                return Err(ModelError::config(
                    "joint_names",
                    format!(
                        "holds {} names: expected one per joint value ({})",
                        names.len(),
                        self.joint_count()
                    ),
                ));
            }
        }
        if self.hidden == 0 {
            return Err(ModelError::config("hidden", "is 0: expected at least 1"));
        }
        if self.frame_joints == Some(true) && self.kind != ModelKind::Attn {
            return Err(frame_joints_refused(self.kind));
        }

        if let Some(latent) = self.latent {
            if self.kind != ModelKind::Attn {
                return Err(latent_refused(self.kind));
            }
            if !(1..=MAX_LATENT).contains(&latent) {
                return Err(ModelError::config(
                    "latent",
                    format!("is {latent}: expected 1 to {MAX_LATENT} latent values"),
                ));
            }
        }
        if self.mirror == Some(0) {
            return Err(ModelError::config(
                "mirror",
                "is 0: expected the width of the joint stage's layers (at least 1), or none",
            ));
        }
        if self.kind == ModelKind::Attn {
            check_heads(self.attention_heads(), self.hidden)?;
        }
        self.image_decoder()?;
        if !(0.0..1.0).contains(&self.sigma_floor) {
            return Err(ModelError::config(
                "sigma_floor",
                format!("is {}: expected a value in [0, 1)", self.sigma_floor),
            ));
        }
        if !(self.joint_weight.is_finite() && self.joint_weight >= 0.0) {
            return Err(ModelError::config(
                "joint_weight",
                format!("is {}: expected a finite value >= 0", self.joint_weight),
            ));
        }
        Ok(())
    }

    /// The image decoder's filters: its upsampling blocks' and its two full-resolution
    /// convolutions' (`decoder_filters`, or the original's: [`decoder_filters`] and
    /// [`IMAGE_DECODER_TAIL`]).
    pub fn image_decoder(&self) -> Result<(Vec<usize>, Vec<usize>), ModelError> {
        let blocks = decoder_filters(self.image_size)?;
        let Some(filters) = &self.decoder_filters else {
            return Ok((blocks, IMAGE_DECODER_TAIL.to_vec()));
        };
        let expected = blocks.len() + IMAGE_DECODER_TAIL.len();
        if filters.len() != expected || filters.contains(&0) {
            return Err(ModelError::config(
                "decoder_filters",
                format!(
                    "is {filters:?}: expected {expected} filter counts above 0 for {size}x{size} \
                     frames ({} upsampling blocks, then {} convolutions at full resolution)",
                    blocks.len(),
                    IMAGE_DECODER_TAIL.len(),
                    size = self.image_size,
                ),
            ));
        }
        let (blocks, tail) = filters.split_at(blocks.len());
        Ok((blocks.to_vec(), tail.to_vec()))
    }

    /// The image encoder's filters: `encoder_filters`, or the original's ([`encoder_filters`]).
    pub fn image_encoder(&self) -> Result<Vec<usize>, ModelError> {
        let original = encoder_filters(self.image_size)?;
        let Some(filters) = &self.encoder_filters else {
            return Ok(original);
        };
        if filters.len() != original.len() || filters.contains(&0) {
            return Err(ModelError::config(
                "encoder_filters",
                format!(
                    "is {filters:?}: expected {} filter counts above 0 for {size}x{size} frames \
                     (one per conv block, each halving the frame down to 2x2)",
                    original.len(),
                    size = self.image_size,
                ),
            ));
        }
        Ok(filters.clone())
    }

    /// Joint values a step (D): `joints`, or the original arm's 7 for files without it.
    pub fn joint_count(&self) -> usize {
        self.joints.unwrap_or(crate::data::JOINTS)
    }

    /// The joint values' names: `joint_names`, or `joint 0` … with the last called `gripper`
    /// (the layout's convention) where the file has none.
    pub fn joint_labels(&self) -> Vec<String> {
        let d = self.joint_count();
        self.joint_names.clone().unwrap_or_else(|| {
            (0..d)
                .map(|j| {
                    if j + 1 == d && d > 1 {
                        "gripper".to_string()
                    } else {
                        format!("joint {j}")
                    }
                })
                .collect()
        })
    }

    /// Heads of the attentive model's attention: `heads`, `ATTENTION_HEADS` (8) by default.
    pub fn attention_heads(&self) -> usize {
        self.heads.unwrap_or(ATTENTION_HEADS)
    }
}

/// The attentive model's default number of attention heads.
pub const ATTENTION_HEADS: usize = 8;

/// Attention splits the H features evenly over the heads.
pub(super) fn check_heads(heads: usize, hidden: usize) -> Result<(), ModelError> {
    if heads == 0 || hidden % heads != 0 {
        return Err(ModelError::config(
            "heads",
            format!("is {heads}: expected a divisor of hidden ({hidden})"),
        ));
    }
    Ok(())
}

/// Filters of the image encoder's conv blocks for frames of `image_size` (the original
/// DMBN's: every block halves the frame, down to 2x2).
pub fn encoder_filters(image_size: usize) -> Result<Vec<usize>, ModelError> {
    match image_size {
        128 => Ok(vec![32, 64, 64, 128, 128, 256]),
        64 => Ok(vec![32, 64, 128, 128, 256]),
        _ => Err(image_size_error(image_size)),
    }
}

/// Filters of the image decoder's upsampling blocks for frames of `image_size` (every block
/// doubles the frame, from 2x2).
pub fn decoder_filters(image_size: usize) -> Result<Vec<usize>, ModelError> {
    match image_size {
        128 => Ok(vec![256, 128, 128, 64, 64, 32]),
        64 => Ok(vec![256, 128, 64, 64, 32]),
        _ => Err(image_size_error(image_size)),
    }
}

fn image_size_error(image_size: usize) -> ModelError {
    ModelError::config(
        "image_size",
        format!("is {image_size}: expected one of {IMAGE_SIZES:?}"),
    )
}

/// The error for a latent path asked of a network without attention.
pub(super) fn latent_refused(kind: ModelKind) -> ModelError {
    ModelError::config(
        "latent",
        format!("is set for a {kind} model: only the attentive model has a latent path"),
    )
}

/// The error for joints read from frames asked of a network without attention.
pub(super) fn frame_joints_refused(kind: ModelKind) -> ModelError {
    ModelError::config(
        "frame_joints",
        format!("is set for a {kind} model: only the attentive model reads joints from frames"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_json_round_trip() {
        let config = ModelConfig::new(ModelKind::Pte);
        assert_eq!(config.image_size, 64);
        assert_eq!(config.hidden, 128);
        assert_eq!(config.sigma_floor, 0.01);
        assert_eq!(config.joint_weight, 0.01);
        let json = serde_json::to_string(&config).unwrap();
        assert!(json.contains("\"kind\":\"pte\""), "{json}");
        let back: ModelConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, config);
    }

    #[test]
    fn bad_fields_are_named() {
        let err = ModelConfig::new(ModelKind::Dmbn)
            .with_image_size(96)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("image_size") && err.contains("96"), "{err}");
        let err = ModelConfig::new(ModelKind::Dmbn)
            .with_sigma_floor(1.0)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("sigma_floor"), "{err}");
        assert!(ModelConfig::new(ModelKind::Dmbn)
            .with_joint_weight(f64::NAN)
            .validate()
            .is_err());
        assert!(ModelConfig::new(ModelKind::Dmbn)
            .with_hidden(0)
            .validate()
            .is_err());
        assert!("pte".parse::<ModelKind>().is_ok());
        assert!("cnp".parse::<ModelKind>().is_err());
        assert_eq!("attn".parse::<ModelKind>().unwrap(), ModelKind::Attn);
        assert!(ModelConfig::new(ModelKind::Attn)
            .with_heads(Some(3))
            .validate()
            .is_err());
        assert!(ModelConfig::new(ModelKind::Attn).validate().is_ok());
        let err = ModelConfig::new(ModelKind::Pte)
            .with_joints(Some(0))
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("joints"), "{err}");
        let err = ModelConfig::new(ModelKind::Pte)
            .with_joints(Some(3))
            .with_joint_names(Some(vec!["a".into(), "b".into()]))
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("joint_names") && err.contains("(3)"), "{err}");
        assert_eq!(ModelConfig::new(ModelKind::Pte).joint_count(), 7);
        assert_eq!(
            ModelConfig::new(ModelKind::Pte)
                .with_joints(Some(3))
                .joint_labels(),
            ["joint 0", "joint 1", "gripper"]
        );
        let narrow = |filters: Vec<usize>| {
            ModelConfig::new(ModelKind::Attn)
                .with_decoder_filters(Some(filters))
                .validate()
        };
        let err = narrow(vec![64, 32, 16]).unwrap_err().to_string();
        assert!(
            err.contains("decoder_filters") && err.contains("expected 7"),
            "{err}"
        );
        let encoder = |filters: Vec<usize>| {
            ModelConfig::new(ModelKind::Pte)
                .with_encoder_filters(Some(filters))
                .validate()
        };
        assert!(encoder(vec![16, 32, 64, 64, 128]).is_ok());
        for bad in [vec![16, 32, 64], vec![16, 32, 0, 64, 128]] {
            let err = encoder(bad).unwrap_err().to_string();
            assert!(
                err.contains("encoder_filters") && err.contains("expected 5"),
                "{err}"
            );
        }
        assert!(narrow(vec![128, 64, 32, 32, 16, 16, 0]).is_err());
        assert!(narrow(vec![128, 64, 32, 32, 16, 16, 8]).is_ok());
    }

    #[test]
    fn decoder_filters_default_to_the_originals_and_split_into_blocks_and_tail() {
        let config = ModelConfig::new(ModelKind::Pte);
        let (blocks, tail) = config.image_decoder().unwrap();
        assert_eq!(blocks, decoder_filters(64).unwrap());
        assert_eq!(tail, IMAGE_DECODER_TAIL);
        let config = config.with_decoder_filters(Some(vec![128, 64, 32, 32, 16, 8, 4]));
        let (blocks, tail) = config.image_decoder().unwrap();
        assert_eq!((blocks, tail), (vec![128, 64, 32, 32, 16], vec![8, 4]));
        // Files written before the field hold the original's.
        let json = r#"{"kind":"attn","image_size":64,"hidden":128,"sigma_floor":0.01,"joint_weight":0.01,"heads":null}"#;
        let old: ModelConfig = serde_json::from_str(json).unwrap();
        assert_eq!(old.decoder_filters, None);
    }

    #[test]
    fn filters_reach_two_pixels() {
        for size in IMAGE_SIZES {
            let enc = encoder_filters(size).unwrap();
            let dec = decoder_filters(size).unwrap();
            assert_eq!(size >> enc.len(), 2);
            assert_eq!(2 << dec.len(), size);
        }
    }
}
