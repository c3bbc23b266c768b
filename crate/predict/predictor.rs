use burn::tensor::{Device, Tensor, TensorData};

use super::{Encoding, Observations, Reads, SequencePrediction};
use crate::augment::Batch;
use crate::data::Joints;
use crate::model::{
    self, tensors, EncodedContexts, JointCorrelation, JointSigmaScale, JointStage, Model,
    ModelError, ModelKind, Normalization, Representation,
};

/// A trained model ready for inference on the CPU (flex backend): encode observations once,
/// decode as many target times as needed. Natively and in wasm alike.
#[derive(Debug)]
pub struct Predictor {
    model: Model,
    normalization: Normalization,
    /// The file's factors on the joint σ (1 without them; `dmbn calibrate`).
    joint_sigma_scale: JointSigmaScale,
    /// How a step's joint errors go together, where the file says (`dmbn calibrate`).
    joint_correlation: Option<JointCorrelation>,
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
            joint_sigma_scale: JointSigmaScale::NONE,
            joint_correlation: None,
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
        let (model, header) = model::load_with_header(bytes, &Device::flex(), kind, image_size)?;
        let scale = header.joint_sigma_scales();
        let correlation = header.joint_correlation()?;
        // One constructor: the loaded weights are frozen as `new`'s are (not compared again
        // on every call).
        Self::new(model, header.normalization)
            .with_joint_sigma_scale(scale)
            .with_joint_correlation(correlation)
    }

    /// The predictor with its joint σ multiplied by `scale` (a calibration fitted after
    /// training; see [`JointSigmaScale`]).
    pub fn with_joint_sigma_scale(mut self, scale: JointSigmaScale) -> Self {
        self.joint_sigma_scale = scale;
        self
    }

    /// The factors on the joint σ: [`JointSigmaScale::NONE`] unless the file was calibrated.
    pub fn joint_sigma_scale(&self) -> JointSigmaScale {
        self.joint_sigma_scale
    }

    /// The predictor whose sampled futures draw each step's joints with `correlation`
    /// (`None`: independently). Fails unless it correlates the model's D joint values.
    pub fn with_joint_correlation(
        mut self,
        correlation: Option<JointCorrelation>,
    ) -> Result<Self, ModelError> {
        if let Some(r) = &correlation {
            if r.joints() != self.joint_count() {
                return Err(ModelError::Header(format!(
                    "joint_correlation is {0} × {0}: expected {1} × {1}, one row per joint value the model predicts",
                    r.joints(),
                    self.joint_count()
                )));
            }
        }
        self.joint_correlation = correlation;
        Ok(self)
    }

    /// How a step's joint errors go together, if the file was calibrated with them.
    pub fn joint_correlation(&self) -> Option<&JointCorrelation> {
        self.joint_correlation.as_ref()
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

    /// Joint values a step (D) the model reads and predicts.
    pub fn joint_count(&self) -> usize {
        self.model.joint_count()
    }

    /// What the decoders condition on (see [`Encoding`]) for `observations` with
    /// blending coefficient `blend`
    /// (1 = images only, 0 = joints only): [`Predictor::encode_contexts`], then
    /// [`Predictor::represent`].
    pub fn encode(&self, observations: &Observations, blend: f32) -> Result<Encoding, ModelError> {
        check_blend(blend)?;
        self.represent(&self.encode_contexts(observations)?, blend)
    }

    /// The observations encoded one by one, not yet aggregated: sets encoded apart can be
    /// joined ([`EncodedContexts::cat`]) or cut ([`EncodedContexts::select`]), so that a new
    /// observation is encoded alone and the others are kept.
    pub fn encode_contexts(
        &self,
        observations: &Observations,
    ) -> Result<EncodedContexts, ModelError> {
        observations.check(self.model.image_size(), self.joint_count())?;
        let batch = self.batch(observations);
        self.model.encode_set(&tensors(&batch, &self.device)?)
    }

    /// What the decoders condition on for encoded observations with blending coefficient
    /// `blend` (1 = images only, 0 = joints only), as [`Predictor::encode`] gives it for the
    /// same observations.
    pub fn represent(
        &self,
        contexts: &EncodedContexts,
        blend: f32,
    ) -> Result<Encoding, ModelError> {
        let reading = match blend == 1.0 {
            true => Reading::Frames,
            false => Reading::None,
        };
        self.represent_reading(contexts, blend, reading)
    }

    /// [`Predictor::represent`] for a sampled future ([`crate::futures`]): its drawn steps are
    /// joints the arm passes through, as the reads of frames are, so with `stage` a model's
    /// joint stage answers between the observations and them whatever the blend (between
    /// them, the network alone lands pushes short); without, the network alone, frames only
    /// too.
    pub fn represent_future(
        &self,
        contexts: &EncodedContexts,
        blend: f32,
        stage: bool,
    ) -> Result<Encoding, ModelError> {
        let reading = match stage {
            true => Reading::Through,
            false => Reading::None,
        };
        self.represent_reading(contexts, blend, reading)
    }

    /// [`Predictor::represent`], with the network's reads at the observed times for the joint
    /// stage as `reading` says, where the model has one.
    fn represent_reading(
        &self,
        contexts: &EncodedContexts,
        blend: f32,
        reading: Reading,
    ) -> Result<Encoding, ModelError> {
        check_blend(blend)?;
        let c = Tensor::<1>::from_data(
            TensorData::new(vec![blend; contexts.batch()], [contexts.batch()]),
            &self.device,
        );
        let observed = contexts.observed_times();
        let span = observed
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        let representation = self.model.represent(contexts, c)?;
        // The joint stage answers from what the network reads at the observed times; a
        // future's at each time once (a bootstrap resample repeats observations, and the
        // stage learnt from distinct glimpses).
        let through = matches!(reading, Reading::Through);
        let reads = match (self.model.joint_stage(), reading) {
            (Some(_), Reading::Frames | Reading::Through) if !observed.is_empty() => {
                let mut times = Vec::with_capacity(observed.len());
                for t in observed {
                    if !(through && times.contains(&t)) {
                        times.push(t);
                    }
                }
                Some(Reads {
                    joints: self.network_joints(&representation, &times)?,
                    times,
                    through,
                })
            }
            _ => None,
        };
        Ok(Encoding {
            representation,
            span,
            reads,
        })
    }

    /// `encoding` with the latent z set to `z` (L values, one sequence) for a model with a
    /// latent path: one sampled future's encoding ([`crate::futures`]). Fails without a path,
    /// for another L, or for an encoding of several sequences.
    pub fn with_latent(&self, encoding: &Encoding, z: &[f32]) -> Result<Encoding, ModelError> {
        let z = Tensor::<2>::from_data(TensorData::new(z.to_vec(), [1, z.len()]), &self.device);
        Ok(Encoding {
            representation: self.model.with_latent(&encoding.representation, z)?,
            ..encoding.clone()
        })
    }

    /// The prediction at `target_times` (finite phases; any number, decoded in chunks of
    /// [`Predictor::CHUNK`]).
    pub fn decode(
        &self,
        encoding: &Encoding,
        target_times: &[f32],
    ) -> Result<SequencePrediction, ModelError> {
        check_times(target_times)?;
        let d = self.joint_count();
        let mut out = SequencePrediction::empty(self.model.image_size(), d);
        for chunk in target_times.chunks(Self::CHUNK) {
            let p = self
                .model
                .decode(&encoding.representation, self.times(chunk))?;
            let mut joint_sigma = model::values(p.joint_sigma);
            for (row, &t) in joint_sigma.chunks_exact_mut(d).zip(chunk) {
                let scale = self
                    .joint_sigma_scale
                    .factor(encoding.is_between_observations(t));
                row.iter_mut().for_each(|s| *s *= scale);
            }
            let mut joint_mean = model::values(p.joint_mean);
            // The stage's joints in the decoders' units (normalised), as `push` takes them.
            self.splice_joint_stage(encoding, chunk, |k, mean, sigma| {
                let row = k * d..(k + 1) * d;
                joint_mean[row.clone()].copy_from_slice(&self.normalization.normalize(mean));
                for (j, s) in joint_sigma[row].iter_mut().enumerate() {
                    *s = sigma[j] / self.normalization.std[j];
                }
            });
            out.push(
                chunk,
                &model::values(p.image_mean),
                &model::values(p.image_sigma),
                &joint_mean,
                &joint_sigma,
                &self.normalization,
            );
        }
        Ok(out)
    }

    /// Where `encoding` has reads for the joint stage: for each of `targets` between the first
    /// and the last observation (the stage interpolates; beyond them the network's joints
    /// stand), `splice(k, mean, σ)` with the stage's joints at target k, in radians and gripper
    /// units. Its σ was fitted on reads of held-out sequences, so the file's σ scales (fitted
    /// to the network's σ) leave it as it is.
    fn splice_joint_stage(
        &self,
        encoding: &Encoding,
        targets: &[f32],
        mut splice: impl FnMut(usize, &[f32], &[f32]),
    ) {
        let (Some(stage), Some(reads)) = (self.model.joint_stage(), encoding.reads.as_ref()) else {
            return;
        };
        let predict = match reads.through {
            true => JointStage::predict_through,
            false => JointStage::predict,
        };
        let (mean, sigma) = predict(stage, &reads.times, &reads.joints, targets, &self.device);
        for (k, &t) in targets.iter().enumerate() {
            if encoding.is_between_observations(t) {
                splice(k, &mean[k], &sigma[k]);
            }
        }
    }

    /// Encode `observations`, then decode `target_times`.
    pub fn predict(
        &self,
        observations: &Observations,
        target_times: &[f32],
        blend: f32,
    ) -> Result<SequencePrediction, ModelError> {
        let encoding = self.encode(observations, blend)?;
        self.decode(&encoding, target_times)
    }

    /// Only the joint means at `target_times` (radians and the gripper value, one row per
    /// target), from `observations` with blend `blend`: [`Predictor::encode`], then
    /// [`Predictor::decode_joints`]. What an arm that imitates needs ([`crate::imitate`]).
    pub fn predict_joints(
        &self,
        observations: &Observations,
        target_times: &[f32],
        blend: f32,
    ) -> Result<Joints, ModelError> {
        check_times(target_times)?;
        self.decode_joints(&self.encode(observations, blend)?, target_times)
    }

    /// Only the joint means at `target_times` for `encoding`: the image decoder, most of a
    /// target's cost, is skipped; frames only (blend 1), a model's joint stage gives them
    /// between the first and the last observation (see [`Encoding::reads`]).
    pub fn decode_joints(
        &self,
        encoding: &Encoding,
        target_times: &[f32],
    ) -> Result<Joints, ModelError> {
        check_times(target_times)?;
        let mut rows = self.network_joints(&encoding.representation, target_times)?;
        self.splice_joint_stage(encoding, target_times, |k, mean, _| {
            rows.row_mut(k).copy_from_slice(mean)
        });
        Ok(rows)
    }

    /// The joint means the network itself decodes at `target_times` from `representation`
    /// (radians and the gripper value), without the image decoder.
    fn network_joints(
        &self,
        representation: &Representation,
        target_times: &[f32],
    ) -> Result<Joints, ModelError> {
        let d = self.joint_count();
        let mut rows = Joints::with_width(d);
        for chunk in target_times.chunks(Self::CHUNK) {
            let (mean, _) = self
                .model
                .decode_joints(representation, self.times(chunk))?;
            for row in model::values(mean).chunks_exact(d) {
                rows.push(&self.normalization.denormalize(row));
            }
        }
        Ok(rows)
    }

    /// The joints the network reads from frames alone (blend 1) at each observed time, in
    /// radians (and gripper units): what the joint stage starts from, and learns from.
    pub fn reads(&self, observations: &Observations) -> Result<Joints, ModelError> {
        let encoding = self.encode(observations, 1.0)?;
        match encoding.reads {
            // A model with a stage read them while encoding.
            Some(reads) => Ok(reads.joints),
            None => self.network_joints(&encoding.representation, &observations.times),
        }
    }

    /// One chunk of target times as the `[1, M]` tensor the decoders take.
    fn times(&self, chunk: &[f32]) -> Tensor<2> {
        Tensor::from_data(
            TensorData::new(chunk.to_vec(), [1, chunk.len()]),
            &self.device,
        )
    }

    /// The one-sequence batch of checked `observations` (no targets: only times are known
    /// at inference, and they are decoded separately; its blend is left at 0, as the blend
    /// is applied when the encodings are represented).
    fn batch(&self, observations: &Observations) -> Batch {
        let (n, s, d) = (
            observations.len(),
            observations.image_size,
            self.joint_count(),
        );
        let mut batch = Batch::contexts_only(1, n, 1, s, d);
        let rows = observations.joints.chunks_exact(d);
        let frames = observations.frames.chunks_exact(3 * s * s);
        for (i, ((frame, row), &time)) in frames.zip(rows).zip(&observations.times).enumerate() {
            batch.set_context(0, i, frame, &self.normalization.normalize(row), time);
        }
        batch
    }
}

/// Fails unless every target time is a finite phase.
fn check_times(target_times: &[f32]) -> Result<(), ModelError> {
    match target_times.iter().find(|t| !t.is_finite()) {
        Some(t) => Err(ModelError::observation(
            "target_times",
            format!("contains {t}: expected finite phases"),
        )),
        None => Ok(()),
    }
}

/// Which reads an encoding keeps for the model's joint stage ([`Reads`]).
#[derive(Debug, Clone, Copy)]
enum Reading {
    /// None: the network answers.
    None,
    /// The network's reads of frames alone, which the stage corrects.
    Frames,
    /// A sampled future's observations and drawn steps, which it passes through.
    Through,
}

/// Fails unless `blend` is a coefficient in [0, 1].
fn check_blend(blend: f32) -> Result<(), ModelError> {
    if (0.0..=1.0).contains(&blend) {
        Ok(())
    } else {
        Err(ModelError::observation(
            "blend",
            format!(
                "is {blend}: expected a coefficient in [0, 1] (1 = images only, 0 = joints only)"
            ),
        ))
    }
}
