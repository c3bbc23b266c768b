use crate::model::Representation;

/// Observations encoded by a [`super::Predictor`]: what its decoders condition on, and the
/// span of the observed times, outside which a calibrated file's joint σ takes its forecast
/// factor ([`crate::model::JointSigmaScale`]).
#[derive(Debug, Clone)]
pub struct Encoding {
    pub representation: Representation,
    /// The first and the last observed time (an empty span, `(∞, −∞)`, without any).
    pub span: (f32, f32),
}
