use burn::module::{Module, ModuleVisitor, Param};
use burn::tensor::{Device, Tensor};

use super::dmbn::Dmbn;
use super::dmbn_attn::DmbnAttn;
use super::dmbn_pte::DmbnPte;
use super::loss::{gaussian_loss, Loss};
use super::{
    BatchTensors, ContextEncodings, Decoder, EncodedContexts, ImageEncoder, JointStage,
    JointStageConfig, LatentGaussian, ModelConfig, ModelError, ModelKind, Prediction,
    Representation, Start,
};

/// One of the three networks.
// One value per model: the size difference between the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Module, Debug)]
pub enum Network {
    /// Time as channel.
    Dmbn(Dmbn),
    /// Positional time encoding.
    Pte(DmbnPte),
    /// Positional time encoding, attentive aggregation.
    Attn(DmbnAttn),
}

/// A DMBN, DMBN-PTE or attentive model with its [`ModelConfig`], so that training,
/// evaluation and inference are written once for all. Its methods check their inputs against the config and return
/// a [`ModelError`] instead of panicking.
#[derive(Module, Debug)]
pub struct Model {
    /// The network's weights.
    pub network: Network,
    /// The joint stage, where the file has one ([`Model::joint_stage`]). Named `mirror`, the
    /// stage's old name, because a field's name is its tensors' name in the model file
    /// (`mirror.layers.0.weight` …): renaming it would orphan every shipped file's stage.
    mirror: Option<JointStage>,
    /// What built it (kind, sizes, σ floor, loss weight).
    #[module(skip)]
    config: ModelConfig,
}

/// The error for a latent asked of a model without a latent path.
fn no_latent_path(kind: ModelKind) -> ModelError {
    ModelError::config(
        "latent",
        format!("this {kind} model has no latent path (train one with --latent L)"),
    )
}

impl ModelConfig {
    /// Validates the config and builds a freshly initialised model on `device`.
    pub fn init(&self, device: &Device) -> Result<Model, ModelError> {
        self.validate()?;
        let network = match self.kind {
            ModelKind::Dmbn => Network::Dmbn(Dmbn::init(self, device)?),
            ModelKind::Pte => Network::Pte(DmbnPte::init(self, device)?),
            ModelKind::Attn => Network::Attn(DmbnAttn::init(self, device)?),
        };
        Ok(Model {
            network,
            mirror: self.mirror.map(|width| {
                JointStageConfig::new()
                    .with_width(width)
                    .with_joints(self.joint_count())
                    .init(device)
            }),
            config: self.clone(),
        })
    }
}

impl Model {
    /// The config the model was built from.
    pub fn config(&self) -> &ModelConfig {
        &self.config
    }

    /// An attentive model that reads joints from frames (`ModelConfig::frame_joints`): one
    /// without a read-out gets one that reads nothing yet, so it predicts as before (training
    /// a shipped file on with `train --init --frame-joints`). Fails for another kind.
    pub fn reading_frame_joints(self, device: &Device) -> Result<Model, ModelError> {
        match self.network {
            Network::Attn(net) => Ok(Model {
                network: Network::Attn(net.reading_frame_joints(device)),
                mirror: self.mirror,
                config: self.config.with_frame_joints(Some(true)),
            }),
            _ => Err(super::config::frame_joints_refused(self.config.kind)),
        }
    }

    /// An attentive model with a latent path of `latent` values ([`super::LatentPath`]): one
    /// without gets one that adds nothing yet, so it predicts as before (`train --init F
    /// --latent L`); one with a path keeps its own. Fails for another kind.
    pub fn with_latent_path(self, latent: usize, device: &Device) -> Result<Model, ModelError> {
        match self.network {
            Network::Attn(net) => {
                let net = net.with_latent_path(latent, device);
                let latent = net.latent.as_ref().map(|path| path.latent());
                let config = self.config.with_latent(latent);
                config.validate()?;
                Ok(Model {
                    network: Network::Attn(net),
                    mirror: self.mirror,
                    config,
                })
            }
            _ => Err(super::config::latent_refused(self.kind())),
        }
    }

    /// L, the size of the global latent z, for a model with a latent path.
    pub fn latent_size(&self) -> Option<usize> {
        self.config.latent
    }

    /// The prior over z given the contexts `representation` holds; none without a latent path.
    pub fn prior(&self, representation: &Representation) -> Option<LatentGaussian> {
        match representation {
            Representation::Attentive(contexts) => contexts.prior.clone(),
            Representation::Mean(_) => None,
        }
    }

    /// The posterior over z given the contexts and the targets' `[B, M, D]` joints
    /// (normalised) at `[B, M]` times (training); none without a latent path.
    pub fn posterior(
        &self,
        representation: &Representation,
        target_times: Tensor<2>,
        target_joints: Tensor<3>,
    ) -> Option<LatentGaussian> {
        match (&self.network, representation) {
            (Network::Attn(net), Representation::Attentive(contexts)) => {
                net.posterior(contexts, target_times, target_joints)
            }
            _ => None,
        }
    }

    /// The representation with z set to `[B, L]` values `z` (drawn from the prior for a
    /// sampled future, or from the posterior in training) in place of the prior's mean.
    /// Fails without a latent path or for a z of another shape.
    pub fn with_latent(
        &self,
        representation: &Representation,
        z: Tensor<2>,
    ) -> Result<Representation, ModelError> {
        let (Network::Attn(net), Representation::Attentive(contexts)) =
            (&self.network, representation)
        else {
            return Err(no_latent_path(self.kind()));
        };
        let Some(path) = &net.latent else {
            return Err(no_latent_path(self.kind()));
        };
        let expected = [contexts.blend.dims()[0], path.latent()];
        if z.dims() != expected {
            return Err(ModelError::Length {
                field: "z",
                expected: expected[0] * expected[1],
                found: z.shape().num_elements(),
                shape: format!("[B={}, L={}]", expected[0], expected[1]),
            });
        }
        let mut contexts = contexts.clone();
        contexts.latent = Some(path.project(z));
        Ok(Representation::Attentive(contexts))
    }

    /// The joint stage, where the model has one: the joints from frames alone, between the
    /// observations.
    pub fn joint_stage(&self) -> Option<&JointStage> {
        self.mirror.as_ref()
    }

    /// The model with `stage` as its joint stage (replacing any it had).
    pub fn with_joint_stage(self, stage: JointStage) -> Model {
        let width = stage.width();
        Model {
            network: self.network,
            mirror: Some(stage),
            config: self.config.with_mirror(Some(width)),
        }
    }

    /// The model without a joint stage (its network changes: the stage learnt the old one's
    /// reads).
    pub fn without_joint_stage(self) -> Model {
        Model {
            network: self.network,
            mirror: None,
            config: self.config.with_mirror(None),
        }
    }

    /// Draws every weight now. burn draws a fresh model's weights lazily, on first use, from a
    /// generator shared by every thread; drawing them right after seeding makes the seed alone
    /// decide them.
    pub fn draw_weights(&self) {
        struct Draw;
        impl ModuleVisitor for Draw {
            fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
                let _ = param.val();
            }
        }
        self.visit(&mut Draw);
    }

    /// Promises that the weights will not change any more, so the image networks' inference
    /// kernels are reused without comparing them with the weights they were prepared from.
    pub fn freeze_kernels(&self) {
        self.image_encoder().kernels.freeze();
        self.decoder().image.kernels.freeze();
    }

    /// Whether [`Model::freeze_kernels`] was called.
    pub fn kernels_frozen(&self) -> bool {
        self.image_encoder().kernels.is_frozen() && self.decoder().image.kernels.is_frozen()
    }

    /// DMBN, DMBN-PTE or the attentive model.
    pub fn kind(&self) -> ModelKind {
        self.config.kind
    }

    /// Frame width and height the model reads and predicts.
    pub fn image_size(&self) -> usize {
        self.config.image_size
    }

    /// Joint values a step (D) the model reads and predicts.
    pub fn joint_count(&self) -> usize {
        self.config.joint_count()
    }

    /// Every context slot's encoding per modality, `[B, N, H]` each: the input of the
    /// paper's time-regression probe.
    pub fn encode_contexts(&self, batch: &BatchTensors) -> Result<ContextEncodings, ModelError> {
        Ok(self.encode_set(batch)?.into_encodings())
    }

    /// The batch's contexts encoded one by one, before they are aggregated: sets can be joined
    /// and cut (see [`EncodedContexts`]), then aggregated with [`Model::represent`].
    pub fn encode_set(&self, batch: &BatchTensors) -> Result<EncodedContexts, ModelError> {
        self.check(batch)?;
        Ok(match &self.network {
            Network::Dmbn(net) => net.encode_set(batch),
            Network::Pte(net) => net.encode_set(batch),
            Network::Attn(net) => net.encode_set(batch),
        })
    }

    /// What the decoders are conditioned on (the blended mean representation, or the
    /// contexts to attend to) for encoded contexts and `[B]` blending coefficients c; decode
    /// it at as many target times as needed with [`Model::decode`]. Fails on contexts another
    /// kind or size of model encoded, or a c per sequence missing.
    pub fn represent(
        &self,
        contexts: &EncodedContexts,
        c: Tensor<1>,
    ) -> Result<Representation, ModelError> {
        let config = &self.config;
        if contexts.kind() != config.kind
            || contexts.hidden() != config.hidden
            || contexts.image_size() != config.image_size
        {
            return Err(ModelError::Contexts(format!(
                "these were encoded by a {} model (H = {}, {}x{} frames), not by this {} model (H = {}, {}x{}): encode with the model that represents",
                contexts.kind(),
                contexts.hidden(),
                contexts.image_size(),
                contexts.image_size(),
                config.kind,
                config.hidden,
                config.image_size,
                config.image_size
            )));
        }
        if c.dims() != [contexts.batch()] {
            return Err(ModelError::Length {
                field: "blend",
                expected: contexts.batch(),
                found: c.shape().num_elements(),
                shape: format!("[B={}]", contexts.batch()),
            });
        }
        Ok(match &self.network {
            Network::Dmbn(net) => Representation::Mean(net.represent(contexts, c)),
            Network::Pte(net) => Representation::Mean(net.represent(contexts, c)),
            Network::Attn(net) => Representation::Attentive(net.represent(contexts, c)),
        })
    }

    /// What the decoders are conditioned on for the batch's contexts: [`Model::encode_set`],
    /// then [`Model::represent`] with the batch's blending coefficients.
    pub fn encode(&self, batch: &BatchTensors) -> Result<Representation, ModelError> {
        self.represent(&self.encode_set(batch)?, batch.blend.clone())
    }

    /// The prediction at `[B, M]` target times (B as the representation, M >= 1).
    pub fn decode(
        &self,
        representation: &Representation,
        target_times: Tensor<2>,
    ) -> Result<Prediction, ModelError> {
        let (x, start) = self.condition(representation, target_times)?;
        Ok(self.decoder().forward(x, start))
    }

    /// Only the joints' mean and σ at `[B, M]` target times, `[B, M, D]` each: the image
    /// decoder, most of a target's cost, is skipped (training uses it to supervise the joints
    /// at many more steps than it decodes frames for).
    pub fn decode_joints(
        &self,
        representation: &Representation,
        target_times: Tensor<2>,
    ) -> Result<(Tensor<3>, Tensor<3>), ModelError> {
        let (x, start) = self.condition(representation, target_times)?;
        Ok(self.decoder().joints(x, start))
    }

    /// The decoders' input at `[B, M]` target times, and where their means start.
    fn condition(
        &self,
        representation: &Representation,
        target_times: Tensor<2>,
    ) -> Result<(Tensor<3>, Option<Start>), ModelError> {
        let batch = representation.batch();
        let found = target_times.dims();
        if found[0] != batch || found[1] == 0 {
            return Err(ModelError::TargetTimes { batch, found });
        }
        Ok(match (&self.network, representation) {
            (Network::Dmbn(net), Representation::Mean(r)) => (net.condition(r, target_times), None),
            (Network::Pte(net), Representation::Mean(r)) => (net.condition(r, target_times), None),
            (Network::Attn(net), Representation::Attentive(c)) => {
                let (x, start) = net.condition(c, target_times);
                (x, Some(start))
            }
            _ => {
                return Err(ModelError::config(
                    "representation",
                    format!(
                        "was not made by this {} model: encode with the model that decodes",
                        self.kind()
                    ),
                ))
            }
        })
    }

    fn image_encoder(&self) -> &ImageEncoder {
        match &self.network {
            Network::Dmbn(n) => &n.image_encoder,
            Network::Pte(n) => &n.image_encoder,
            Network::Attn(n) => &n.image_encoder,
        }
    }

    fn decoder(&self) -> &Decoder {
        match &self.network {
            Network::Dmbn(n) => &n.decoder,
            Network::Pte(n) => &n.decoder,
            Network::Attn(n) => &n.decoder,
        }
    }

    /// Encode the batch's contexts and decode its target times (training).
    pub fn forward(&self, batch: &BatchTensors) -> Result<Prediction, ModelError> {
        let representation = self.encode(batch)?;
        self.decode(&representation, batch.target_times.clone())
    }

    /// The loss of a prediction made for `batch`, which must hold target frames and joints;
    /// its total as β-NLL when `beta` > 0 (see [`gaussian_loss`]).
    pub fn loss(
        &self,
        prediction: &Prediction,
        batch: &BatchTensors,
        beta: f64,
    ) -> Result<Loss, ModelError> {
        let images = batch
            .target_images
            .clone()
            .ok_or(ModelError::MissingTargets {
                field: "target_images",
            })?;
        let joints = batch
            .target_joints
            .clone()
            .ok_or(ModelError::MissingTargets {
                field: "target_joints",
            })?;
        if images.dims() != prediction.image_mean.dims() {
            return Err(ModelError::Length {
                field: "target_images",
                expected: prediction.image_mean.shape().num_elements(),
                found: images.shape().num_elements(),
                shape: format!("{:?}", prediction.image_mean.dims()),
            });
        }
        if joints.dims() != prediction.joint_mean.dims() {
            return Err(ModelError::Length {
                field: "target_joints",
                expected: prediction.joint_mean.shape().num_elements(),
                found: joints.shape().num_elements(),
                shape: format!("{:?}", prediction.joint_mean.dims()),
            });
        }
        Ok(gaussian_loss(
            prediction,
            images,
            joints,
            self.config.joint_weight,
            beta,
        ))
    }

    fn check(&self, batch: &BatchTensors) -> Result<(), ModelError> {
        if batch.image_size != self.config.image_size {
            return Err(ModelError::ImageSize {
                expected: self.config.image_size,
                found: batch.image_size,
            });
        }
        let found = batch.context_joints.dims()[2];
        if found != self.joint_count() {
            return Err(ModelError::JointCount {
                expected: self.joint_count(),
                found,
            });
        }
        Ok(())
    }
}
