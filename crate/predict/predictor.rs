use burn::tensor::{Device, Tensor, TensorData};

use super::{Observations, SequencePrediction};
use crate::augment::Batch;
use crate::data::JOINTS;
use crate::model::{self, tensors, Model, ModelError, ModelKind, Normalization, Representation};

/// A trained model ready for inference on the CPU (flex backend): encode observations once,
/// decode as many target times as needed. Natively and in wasm alike.
#[derive(Debug)]
pub struct Predictor {
    model: Model,
    normalization: Normalization,
    device: Device,
}

impl Predictor {
    /// Target times decoded per forward pass: bounds the activations' memory (at 128 px
    /// too) while keeping the matrix products large enough to be efficient.
    pub const CHUNK: usize = 25;

    /// A predictor for `model`, which must live on `Device::flex()`, trained with `normalization`.
    /// The predictor only reads the model, so its inference kernels are frozen.
    pub fn new(model: Model, normalization: Normalization) -> Self {
        model.freeze_kernels();
        Predictor {
            model,
            normalization,
            device: Device::flex(),
        }
    }

    /// The model file in `bytes` (see [`crate::model::file`]).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, ModelError> {
        Self::from_bytes_expecting(bytes, None, None)
    }

    /// As [`Predictor::from_bytes`], failing unless the file holds a `kind` model and/or one
    /// for `image_size` frames.
    pub fn from_bytes_expecting(
        bytes: &[u8],
        kind: Option<ModelKind>,
        image_size: Option<usize>,
    ) -> Result<Self, ModelError> {
        let (model, normalization, _) =
            model::load_bytes_expecting(bytes, &Device::flex(), kind, image_size)?;
        // One constructor: the loaded weights are frozen as `new`'s are (not compared again
        // on every call).
        Ok(Self::new(model, normalization))
    }

    /// The model file at `path`.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Self, ModelError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(ModelError::io(path))?;
        Self::from_bytes(&bytes).map_err(ModelError::in_file(path))
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The joint statistics the model was trained with.
    pub fn normalization(&self) -> &Normalization {
        &self.normalization
    }

    /// What the decoders condition on (see [`Representation`]) for `observations` with
    /// blending coefficient `blend`
    /// (1 = images only, 0 = joints only).
    pub fn encode(
        &self,
        observations: &Observations,
        blend: f32,
    ) -> Result<Representation, ModelError> {
        if !(0.0..=1.0).contains(&blend) {
            return Err(ModelError::observation(
                "blend",
                format!("is {blend}: expected a coefficient in [0, 1] (1 = images only, 0 = joints only)"),
            ));
        }
        observations.check(self.model.image_size())?;
        let batch = self.batch(observations, blend);
        self.model.encode(&tensors(&batch, &self.device)?)
    }

    /// The prediction at `target_times` (finite phases; any number, decoded in chunks of
    /// [`Predictor::CHUNK`]).
    pub fn decode(
        &self,
        representation: &Representation,
        target_times: &[f32],
    ) -> Result<SequencePrediction, ModelError> {
        if let Some(t) = target_times.iter().find(|t| !t.is_finite()) {
            return Err(ModelError::observation(
                "target_times",
                format!("contains {t}: expected finite phases"),
            ));
        }
        let mut out = SequencePrediction::empty(self.model.image_size());
        for chunk in target_times.chunks(Self::CHUNK) {
            let times = Tensor::<2>::from_data(
                TensorData::new(chunk.to_vec(), [1, chunk.len()]),
                &self.device,
            );
            let p = self.model.decode(representation, times)?;
            out.push(
                chunk,
                &model::values(p.image_mean),
                &model::values(p.image_sigma),
                &model::values(p.joint_mean),
                &model::values(p.joint_sigma),
                &self.normalization,
            );
        }
        Ok(out)
    }

    /// Encode `observations`, then decode `target_times`.
    pub fn predict(
        &self,
        observations: &Observations,
        target_times: &[f32],
        blend: f32,
    ) -> Result<SequencePrediction, ModelError> {
        let representation = self.encode(observations, blend)?;
        self.decode(&representation, target_times)
    }

    /// The one-sequence batch of checked `observations` (no targets: only times are known
    /// at inference, and they are decoded separately).
    fn batch(&self, observations: &Observations, blend: f32) -> Batch {
        let (n, s) = (observations.len(), observations.image_size);
        let mut batch = Batch::contexts_only(1, n, 1, s);
        let rows = observations.joints.chunks_exact(JOINTS);
        let frames = observations.frames.chunks_exact(3 * s * s);
        for (i, ((frame, row), &time)) in frames.zip(rows).zip(&observations.times).enumerate() {
            let row: [f32; JOINTS] = std::array::from_fn(|j| row[j]);
            batch.set_context(0, i, frame, self.normalization.normalize(&row), time);
        }
        batch.blend[0] = blend;
        batch
    }
}
