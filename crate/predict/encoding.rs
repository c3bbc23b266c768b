use crate::model::Representation;

/// Observations encoded by a [`super::Predictor`]: what its decoders condition on, and the
/// span of the observed times, outside which a calibrated file's joint σ takes its forecast
/// factor ([`crate::model::JointSigmaScale`]).
#[derive(Debug, Clone)]
pub struct Encoding {
    pub representation: Representation,
    /// The first and the last observed time (an empty span, `(∞, −∞)`, without any).
    pub span: (f32, f32),
    /// Where the model has a mirror stage and the observations are frames only (blend 1):
    /// the joints its network read at the observed times, which the stage turns into the
    /// joints at every target between the first and the last of them
    /// ([`crate::model::Mirror`]; beyond them, forecasting, the network's own).
    pub reads: Option<Reads>,
}

/// The joints a network read from frames alone at the observed times.
#[derive(Debug, Clone, PartialEq)]
pub struct Reads {
    /// The observed times (phases).
    pub times: Vec<f32>,
    /// The joints read at each, in radians (and gripper units).
    pub joints: crate::data::Joints,
}
