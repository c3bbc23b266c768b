//! The model file: one self-describing file holding the config, the joint normalisation and
//! the weights.
//!
//! ```text
//! offset      size  content
//! 0           8     magic "DMBNMODL"
//! 8           4     format version, u32 little-endian (currently 1)
//! 12          4     header length H, u32 little-endian
//! 16          H     header, UTF-8 JSON (see ModelHeader)
//! 16+H        8     weights length W, u64 little-endian
//! 24+H        W     weights, burnpack (burn-store), f32 or f16
//! ```
//!
//! Nothing may follow the weights. The header's `weights.sha256` covers the W weight bytes.
//! A joint stage ([`super::JointStage`]) is stored under its old name, `mirror`: its width
//! as the config's `mirror`, its tensors as `mirror.…`, so that files written before the
//! rename load as they were.
use burn::module::Module;
use burn::store::{BurnpackStore, HalfPrecisionAdapter, ModuleSnapshot};
use burn::tensor::{Bytes, Device};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{
    JointCorrelation, JointSigmaScale, Model, ModelConfig, ModelError, ModelKind, Normalization,
};

/// The first 8 bytes of every model file.
pub const MAGIC: &[u8; 8] = b"DMBNMODL";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// How the weights are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WeightDType {
    /// 32-bit floats, exactly the trained weights.
    F32,
    /// 16-bit floats: half the size; loading converts back to f32.
    F16,
}

/// Where and what the weights are.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WeightsInfo {
    /// Container format of the weight section: `"burnpack"`.
    pub format: String,
    /// Float type of the stored weights.
    pub dtype: WeightDType,
    /// Length of the weight section in bytes.
    pub bytes: u64,
    /// SHA-256 of the weight section, lowercase hex.
    pub sha256: String,
    /// Number of scalar parameters.
    pub parameters: u64,
}

/// The JSON header: everything needed to rebuild the model before reading its weights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelHeader {
    /// What wrote the file (`dmbn <version>`).
    pub producer: String,
    /// Model kind and every hyperparameter.
    pub config: ModelConfig,
    /// Joint statistics the model was trained with.
    pub normalization: Normalization,
    /// A factor on every predicted joint σ, fitted after training on sequences the model did
    /// not train on (`dmbn calibrate`) so that mean ± 2σ holds about 95% of the truth; absent:
    /// 1 (the σ as trained). With [`ModelHeader::forecast_joint_sigma_scale`], only between
    /// the observations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_sigma_scale: Option<f32>,
    /// The factor at target times outside the span of the observed times (forecasting),
    /// fitted apart because a model's error grows differently there; absent: the
    /// [`ModelHeader::joint_sigma_scale`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forecast_joint_sigma_scale: Option<f32>,
    /// How a step's joint errors go together ([`JointCorrelation`]: R, row-major D × D),
    /// fitted with the σ scales; sampled futures draw each step's joints with it. Absent:
    /// each joint drawn on its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation: Option<Vec<f32>>,
    /// Where the file holds K > 1 regions' R (`joint_correlation`: K × D × D), their centres,
    /// K × D normalised joint values: a draw takes the R whose centre is nearest its mean.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation_centres: Option<Vec<f32>>,
    /// Where the regions were fitted per drawn step, their phases (K, 0-1): a draw takes the
    /// R among those fitted at the phase nearest its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation_phases: Option<Vec<f32>>,
    /// The weight section.
    pub weights: WeightsInfo,
}

impl ModelHeader {
    /// The file's joint σ scales ([`JointSigmaScale::NONE`] when it was never calibrated).
    pub fn joint_sigma_scales(&self) -> JointSigmaScale {
        JointSigmaScale {
            between: self.joint_sigma_scale.unwrap_or(1.0),
            forecast: self.forecast_joint_sigma_scale,
        }
    }

    /// The file's [`JointCorrelation`], if it holds one (checked when the file is read).
    pub fn joint_correlation(&self) -> Result<Option<JointCorrelation>, ModelError> {
        let joints = self.config.joint_count();
        let centres = self.joint_correlation_centres.clone();
        let phases = self.joint_correlation_phases.clone();
        (self.joint_correlation.clone())
            .map(|values| {
                JointCorrelation::with_regions("joint_correlation", values, centres, phases, joints)
            })
            .transpose()
    }
}

/// The model file's bytes: the model's config and weights (in f16 when `half`) with the joint
/// normalisation it was trained with.
pub fn save_bytes(
    model: &Model,
    normalization: &Normalization,
    half: bool,
) -> Result<Vec<u8>, ModelError> {
    check_normalization(normalization, model.joint_count())?;
    let mut store = BurnpackStore::from_bytes(None);
    if half {
        store = store.with_to_adapter(HalfPrecisionAdapter::new());
    }
    model
        .save_into(&mut store)
        .map_err(|e| ModelError::Weights(format!("cannot serialise the weights: {e}")))?;
    let weights = store
        .get_bytes()
        .map_err(|e| ModelError::Weights(format!("cannot serialise the weights: {e}")))?;
    let header = ModelHeader {
        producer: format!("dmbn {}", env!("CARGO_PKG_VERSION")),
        config: model.config().clone(),
        normalization: normalization.clone(),
        joint_sigma_scale: None,
        forecast_joint_sigma_scale: None,
        joint_correlation: None,
        joint_correlation_centres: None,
        joint_correlation_phases: None,
        weights: WeightsInfo {
            format: "burnpack".into(),
            dtype: if half {
                WeightDType::F16
            } else {
                WeightDType::F32
            },
            bytes: weights.len() as u64,
            sha256: hex(&Sha256::digest(&weights[..])),
            parameters: model.num_params() as u64,
        },
    };
    assemble(&header, &weights)
}

/// The model file `bytes` with its joint σ scales set to `scale` (see
/// [`ModelHeader::joint_sigma_scale`] and [`ModelHeader::forecast_joint_sigma_scale`]); the
/// weights are kept as they are.
pub fn with_joint_sigma_scale(bytes: &[u8], scale: JointSigmaScale) -> Result<Vec<u8>, ModelError> {
    check_joint_sigma_scale("joint_sigma_scale", Some(scale.between))?;
    check_joint_sigma_scale("forecast_joint_sigma_scale", scale.forecast)?;
    let (mut header, weights) = split(bytes)?;
    header.joint_sigma_scale = Some(scale.between);
    header.forecast_joint_sigma_scale = scale.forecast;
    assemble(&header, weights)
}

/// The model file `bytes` with its [`JointCorrelation`] set to `correlation` (removed for
/// `None`); the weights are kept as they are.
pub fn with_joint_correlation(
    bytes: &[u8],
    correlation: Option<&JointCorrelation>,
) -> Result<Vec<u8>, ModelError> {
    let (mut header, weights) = split(bytes)?;
    header.joint_correlation = correlation.map(|r| r.values());
    header.joint_correlation_centres = correlation.and_then(|r| r.centres());
    header.joint_correlation_phases = correlation.and_then(|r| r.phases());
    header.joint_correlation()?;
    assemble(&header, weights)
}

/// A joint σ scale, if any, is a finite number above 0.
fn check_joint_sigma_scale(field: &str, scale: Option<f32>) -> Result<(), ModelError> {
    match scale {
        Some(s) if !(s.is_finite() && s > 0.0) => Err(ModelError::Header(format!(
            "{field} is {s}: expected a finite number above 0"
        ))),
        _ => Ok(()),
    }
}

/// The file's bytes: magic, version, `header` as JSON and `weights`.
fn assemble(header: &ModelHeader, weights: &[u8]) -> Result<Vec<u8>, ModelError> {
    let header = serde_json::to_vec_pretty(header)
        .map_err(|e| ModelError::Header(format!("cannot write the header: {e}")))?;
    let header_len = u32::try_from(header.len())
        .map_err(|_| ModelError::Header("header longer than 4 GiB".into()))?;
    let mut out = Vec::with_capacity(24 + header.len() + weights.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&(weights.len() as u64).to_le_bytes());
    out.extend_from_slice(weights);
    Ok(out)
}

/// Reads a model file's header (and checks the framing) without building the model.
pub fn read_header(bytes: &[u8]) -> Result<ModelHeader, ModelError> {
    Ok(split(bytes)?.0)
}

/// Rebuilds the model saved in `bytes` on `device`, with its normalisation and config.
pub fn load_bytes(
    bytes: &[u8],
    device: &Device,
) -> Result<(Model, Normalization, ModelConfig), ModelError> {
    load_bytes_expecting(bytes, device, None, None)
}

/// As [`load_bytes`], and fails unless the file holds a model of `kind` and/or for frames of
/// `image_size` (when given).
pub fn load_bytes_expecting(
    bytes: &[u8],
    device: &Device,
    kind: Option<ModelKind>,
    image_size: Option<usize>,
) -> Result<(Model, Normalization, ModelConfig), ModelError> {
    let (model, header) = load_with_header(bytes, device, kind, image_size)?;
    Ok((model, header.normalization, header.config))
}

/// As [`load_bytes_expecting`], with the whole header (the joint σ scale too): the file is
/// framed, parsed and checksummed once.
pub fn load_with_header(
    bytes: &[u8],
    device: &Device,
    kind: Option<ModelKind>,
    image_size: Option<usize>,
) -> Result<(Model, ModelHeader), ModelError> {
    let (header, weights) = split(bytes)?;
    let config = &header.config;
    if let Some(expected) = kind {
        if config.kind != expected {
            return Err(ModelError::Kind {
                expected: expected.to_string(),
                found: config.kind.to_string(),
            });
        }
    }
    if let Some(expected) = image_size {
        if config.image_size != expected {
            return Err(ModelError::FileImageSize {
                expected,
                found: config.image_size,
            });
        }
    }
    let mut model = config.init(device)?;
    let mut store = BurnpackStore::from_bytes(Some(Bytes::from_bytes_vec(weights.to_vec())));
    if header.weights.dtype == WeightDType::F16 {
        store = store.with_from_adapter(HalfPrecisionAdapter::new());
    }
    let result = model
        .load_from(&mut store)
        .map_err(|e| ModelError::Weights(e.to_string()))?;
    if !result.unused.is_empty() {
        return Err(ModelError::Weights(format!(
            "tensors the {} model does not have: {:?}",
            config.kind, result.unused
        )));
    }
    Ok((model, header))
}

/// Checks the framing, parses and validates the header, checks the weights' checksum and
/// returns the header with the weight section.
fn split(bytes: &[u8]) -> Result<(ModelHeader, &[u8]), ModelError> {
    if bytes.len() < MAGIC.len() {
        return Err(if MAGIC.starts_with(bytes) && !bytes.is_empty() {
            ModelError::Truncated {
                what: "the magic bytes",
                expected: MAGIC.len(),
                found: bytes.len(),
            }
        } else {
            ModelError::NotAModelFile
        });
    }
    let mut reader = Reader { bytes };
    if reader.take("the magic bytes", MAGIC.len())? != MAGIC {
        return Err(ModelError::NotAModelFile);
    }
    let version = u32::from_le_bytes(reader.array("the format version")?);
    if version != FORMAT_VERSION {
        return Err(ModelError::Version {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let header_len = u32::from_le_bytes(reader.array("the header length")?) as usize;
    let header = reader.take("the header", header_len)?;
    let header: ModelHeader =
        serde_json::from_slice(header).map_err(|e| ModelError::Header(e.to_string()))?;
    header.config.validate()?;
    check_normalization(&header.normalization, header.config.joint_count())?;
    check_joint_sigma_scale("joint_sigma_scale", header.joint_sigma_scale)?;
    check_joint_sigma_scale(
        "forecast_joint_sigma_scale",
        header.forecast_joint_sigma_scale,
    )?;
    header.joint_correlation()?;
    if header.weights.format != "burnpack" {
        return Err(ModelError::Header(format!(
            "weights.format is {:?}: expected \"burnpack\"",
            header.weights.format
        )));
    }
    let weights_len = u64::from_le_bytes(reader.array("the weights length")?);
    if weights_len != header.weights.bytes {
        return Err(ModelError::Header(format!(
            "weights.bytes is {}, but the weight section holds {weights_len}",
            header.weights.bytes
        )));
    }
    let weights_len = usize::try_from(weights_len).map_err(|_| ModelError::Truncated {
        what: "the weights",
        expected: usize::MAX,
        found: reader.bytes.len(),
    })?;
    let weights = reader.take("the weights", weights_len)?;
    if !reader.bytes.is_empty() {
        return Err(ModelError::TrailingBytes {
            found: reader.bytes.len(),
        });
    }
    if hex(&Sha256::digest(weights)) != header.weights.sha256 {
        return Err(ModelError::Checksum);
    }
    Ok((header, weights))
}

/// A cursor over the file's bytes whose reads fail with [`ModelError::Truncated`].
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, what: &'static str, len: usize) -> Result<&'a [u8], ModelError> {
        if self.bytes.len() < len {
            return Err(ModelError::Truncated {
                what,
                expected: len,
                found: self.bytes.len(),
            });
        }
        let (head, rest) = self.bytes.split_at(len);
        self.bytes = rest;
        Ok(head)
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], ModelError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(what, N)?);
        Ok(out)
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks that there are `d` joint means and standard deviations, every mean finite and every
/// standard deviation finite and positive.
fn check_normalization(n: &Normalization, d: usize) -> Result<(), ModelError> {
    if n.mean.len() != d || n.std.len() != d {
        return Err(ModelError::Header(format!(
            "normalization holds {} means and {} standard deviations: expected {d}, one per joint value of the model",
            n.mean.len(),
            n.std.len()
        )));
    }
    for (index, &value) in n.mean.iter().enumerate() {
        if !value.is_finite() {
            return Err(ModelError::Normalization {
                field: "mean",
                index,
                value,
                expected: "a finite number",
            });
        }
    }
    for (index, &value) in n.std.iter().enumerate() {
        if !(value.is_finite() && value > 0.0) {
            return Err(ModelError::Normalization {
                field: "std",
                index,
                value,
                expected: "a finite number above 0",
            });
        }
    }
    Ok(())
}
