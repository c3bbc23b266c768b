//! The model as a safetensors file for PyTorch: every tensor under the name and in the layout
//! of its PyTorch twin (`python/dmbn_torch/`: Conv2d `[out, in, kh, kw]`, Linear
//! `[out, in]`, LayerNorm `weight`/`bias`), and the model file's header (kind,
//! hyperparameters, image size, joint normalisation) as the metadata entry `dmbn`.
//!
//! Names are the model's module paths without the `network` prefix and the variant
//! (`decoder.shared.weight`, `image_attention.query.bias` …; the joint stage's, under its
//! old name, `mirror.layers.0.weight` …); burn-store's PyTorch adapters
//! transpose the Linear weights and rename LayerNorm's gamma/beta. Export and import go
//! through the model file's bytes, so what is imported runs wherever a model file does.
use std::collections::HashMap;

use burn::store::{
    BurnToPyTorchAdapter, FloatCastAdapter, KeyRemapper, ModuleAdapter, ModuleSnapshot,
    PyTorchToBurnAdapter, SafetensorsStore,
};
use burn::tensor::{DType, Device};
use safetensors::{Dtype, SafeTensors};
use serde::{Deserialize, Serialize};

use super::{
    load_with_header, save_bytes, JointCorrelation, JointSigmaScale, Model, ModelConfig,
    ModelError, Normalization,
};

/// The metadata key holding [`SafetensorsHeader`] as JSON.
pub const METADATA_KEY: &str = "dmbn";

/// What the `dmbn` metadata entry holds: everything needed to rebuild the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SafetensorsHeader {
    /// What wrote the file (`dmbn <version>`, or the PyTorch twin).
    pub producer: String,
    /// Model kind and every hyperparameter.
    pub config: ModelConfig,
    /// Joint statistics the model was trained with.
    pub normalization: Normalization,
    /// The model file's factor on every joint σ, if it was calibrated (between the
    /// observations only when the forecast one is given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_sigma_scale: Option<f32>,
    /// The model file's factor on the joint σ outside the observed times' span, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forecast_joint_sigma_scale: Option<f32>,
    /// The model file's joint correlation for sampled futures, if any (row-major D × D, or
    /// K × D × D for K regions).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation: Option<Vec<f32>>,
    /// Its regions' centres where it holds several (K × D normalised joint values).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation_centres: Option<Vec<f32>>,
    /// Their phases where they were fitted per drawn step (K).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_correlation_phases: Option<Vec<f32>>,
}

/// The model file in `model_file` as safetensors bytes, f32 (or f16 when `half`).
pub fn export_safetensors(model_file: &[u8], half: bool) -> Result<Vec<u8>, ModelError> {
    let (model, file) = load_with_header(model_file, &Device::flex(), None, None)?;
    let header = SafetensorsHeader {
        producer: format!("dmbn {}", env!("CARGO_PKG_VERSION")),
        config: file.config,
        normalization: file.normalization,
        joint_sigma_scale: file.joint_sigma_scale,
        forecast_joint_sigma_scale: file.forecast_joint_sigma_scale,
        joint_correlation: file.joint_correlation,
        joint_correlation_centres: file.joint_correlation_centres,
        joint_correlation_phases: file.joint_correlation_phases,
    };
    let header = serde_json::to_string(&header)
        .map_err(|e| ModelError::Header(format!("cannot write the metadata: {e}")))?;
    let adapter = BurnToPyTorchAdapter.chain(FloatCastAdapter::to(if half {
        DType::F16
    } else {
        DType::F32
    }));
    let mut store = SafetensorsStore::from_bytes(None)
        .skip_enum_variants(true)
        .remap(remapper("^network\\.", ""))
        .with_to_adapter(adapter)
        .metadata(METADATA_KEY, header);
    model
        .save_into(&mut store)
        .map_err(|e| ModelError::Weights(format!("cannot write the safetensors: {e}")))?;
    store
        .get_bytes()
        .map_err(|e| ModelError::Weights(format!("cannot write the safetensors: {e}")))
}

/// The safetensors file in `bytes` (as [`export_safetensors`] writes it, or PyTorch's
/// `safetensors.torch.save_file` with the `dmbn` metadata) as a model file's bytes, with f16
/// weights when `half`. Every tensor is checked by name and shape before any is read.
pub fn import_safetensors(bytes: &[u8], half: bool) -> Result<Vec<u8>, ModelError> {
    if bytes.starts_with(super::file::MAGIC) {
        return Err(ModelError::Safetensors(
            "this is a dmbn model file, not safetensors: it runs as it is (`dmbn export` makes \
             safetensors of it)"
                .into(),
        ));
    }
    let file = SafeTensors::deserialize(bytes)
        .map_err(|e| ModelError::Safetensors(format!("not a readable safetensors file: {e}")))?;
    let header = read_metadata(bytes)?;
    header.config.validate()?;
    let mut model = header.config.init(&Device::flex())?;
    check_tensors(&file, &expected_tensors(&model), &header.config)?;
    let mut store = SafetensorsStore::from_bytes(Some(bytes.to_vec()))
        .skip_enum_variants(true)
        .remap(
            remapper("^", "network.")
                .add_pattern("^network\\.mirror\\.", "mirror.")
                .expect("a valid constant pattern"),
        )
        .with_from_adapter(PyTorchToBurnAdapter.chain(FloatCastAdapter::to(DType::F32)))
        .validate(false)
        .allow_partial(true);
    let result = model
        .load_from(&mut store)
        .map_err(|e| ModelError::Safetensors(e.to_string()))?;
    if let Some(error) = result.errors.first() {
        return Err(ModelError::Safetensors(error.to_string()));
    }
    if let Some((path, _)) = result.missing.first() {
        return Err(ModelError::Safetensors(format!(
            "tensor `{path}` is missing"
        )));
    }
    let mut bytes = save_bytes(&model, &header.normalization, half)?;
    let (between, forecast) = (header.joint_sigma_scale, header.forecast_joint_sigma_scale);
    if between.is_some() || forecast.is_some() {
        let scale = JointSigmaScale {
            between: between.unwrap_or(1.0),
            forecast,
        };
        bytes = super::with_joint_sigma_scale(&bytes, scale)?;
    }
    match header.joint_correlation {
        Some(values) => {
            let joints = header.config.joint_count();
            let (centres, phases) = (
                header.joint_correlation_centres,
                header.joint_correlation_phases,
            );
            let correlation = JointCorrelation::with_regions(
                "joint_correlation",
                values,
                centres,
                phases,
                joints,
            )?;
            super::with_joint_correlation(&bytes, Some(&correlation))
        }
        None => Ok(bytes),
    }
}

/// The `dmbn` metadata entry of a safetensors file.
pub fn read_metadata(bytes: &[u8]) -> Result<SafetensorsHeader, ModelError> {
    let (_, metadata) = SafeTensors::read_metadata(bytes)
        .map_err(|e| ModelError::Safetensors(format!("not a readable safetensors file: {e}")))?;
    let json = metadata
        .metadata()
        .as_ref()
        .and_then(|m| m.get(METADATA_KEY))
        .ok_or_else(|| {
            ModelError::Safetensors(format!(
                "no `{METADATA_KEY}` metadata: expected the model's kind, config and joint \
                 normalisation as JSON (files written by `dmbn export` or python/dmbn_torch \
                 `save` have it)"
            ))
        })?;
    serde_json::from_str(json)
        .map_err(|e| ModelError::Safetensors(format!("bad `{METADATA_KEY}` metadata: {e}")))
}

/// Name → PyTorch shape of every tensor of `model`, as export names them.
fn expected_tensors(model: &Model) -> HashMap<String, Vec<usize>> {
    let adapter: Box<dyn ModuleAdapter> = Box::new(BurnToPyTorchAdapter);
    model
        .collect(None, Some(adapter), true)
        .into_iter()
        .map(|t| {
            let name = t
                .name
                .strip_prefix("network.")
                .unwrap_or(&t.name)
                .to_string();
            (name, t.shape.iter().copied().collect())
        })
        .collect()
}

/// Every expected tensor present with its shape and a float type, and nothing else.
fn check_tensors(
    file: &SafeTensors,
    expected: &HashMap<String, Vec<usize>>,
    config: &ModelConfig,
) -> Result<(), ModelError> {
    let mut names: Vec<&String> = expected.keys().collect();
    names.sort();
    // Missing tensors first: a file of another kind or size lacks some, and says so best.
    if let Some(name) = names.iter().find(|n| file.tensor(n).is_err()) {
        return Err(ModelError::Safetensors(format!(
            "tensor `{name}` is missing: a {} model for {}-px frames has it",
            config.kind, config.image_size
        )));
    }
    for name in names {
        let view = file
            .tensor(name)
            .map_err(|e| ModelError::Safetensors(format!("tensor `{name}`: {e}")))?;
        let want = &expected[name];
        if view.shape() != want.as_slice() {
            return Err(ModelError::Safetensors(format!(
                "tensor `{name}` has shape {:?}, expected {want:?} (PyTorch layout) for a {} \
                 model for {}-px frames",
                view.shape(),
                config.kind,
                config.image_size
            )));
        }
        if !matches!(
            view.dtype(),
            Dtype::F16 | Dtype::BF16 | Dtype::F32 | Dtype::F64
        ) {
            return Err(ModelError::Safetensors(format!(
                "tensor `{name}` holds {:?}: expected floats (F32, F16, BF16 or F64)",
                view.dtype()
            )));
        }
    }
    let mut extra: Vec<String> = file
        .names()
        .into_iter()
        .filter(|n| !expected.contains_key(*n))
        .map(str::to_string)
        .collect();
    extra.sort();
    if !extra.is_empty() {
        return Err(ModelError::Safetensors(format!(
            "tensors a {} model does not have: {extra:?}",
            config.kind
        )));
    }
    Ok(())
}

fn remapper(from: &str, to: &str) -> KeyRemapper {
    KeyRemapper::new()
        .add_pattern(from, to)
        .expect("a valid constant pattern")
}

/// [`export_safetensors`] of the model file at `path`; errors name the file.
pub fn export_file(path: &std::path::Path, half: bool) -> Result<Vec<u8>, ModelError> {
    let bytes = std::fs::read(path).map_err(ModelError::io(path))?;
    export_safetensors(&bytes, half).map_err(ModelError::in_file(path))
}

/// [`import_safetensors`] of the safetensors file at `path`; errors name the file.
pub fn import_file(path: &std::path::Path, half: bool) -> Result<Vec<u8>, ModelError> {
    let bytes = std::fs::read(path).map_err(ModelError::io(path))?;
    import_safetensors(&bytes, half).map_err(ModelError::in_file(path))
}
