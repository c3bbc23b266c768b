use crate::model::Representation;

/// Observations encoded by a [`super::Predictor`]: what its decoders condition on, and the
/// span of the observed times, outside which a calibrated file's joint σ takes its forecast
/// factor ([`crate::model::JointSigmaScale`]).
#[derive(Debug, Clone)]
pub struct Encoding {
    pub representation: Representation,
    /// The first and the last observed time (an empty span, `(∞, −∞)`, without any).
    pub span: (f32, f32),
    /// Where the model has a joint stage and the observations are frames only (blend 1):
    /// the joints its network read at the observed times, which the stage turns into the
    /// joints at every target between the first and the last of them
    /// ([`crate::model::JointStage`]; beyond them, forecasting, the network's own).
    pub reads: Option<Reads>,
}

impl Encoding {
    /// Whether target time `t` lies between the first and the last observed time (both
    /// included): there the model interpolates, so the joint stage answers and a calibrated
    /// file's `between` σ factor applies; outside, it forecasts. Never, without observations.
    pub fn is_between_observations(&self, t: f32) -> bool {
        (self.span.0..=self.span.1).contains(&t)
    }
}

/// The joints a network read from frames alone at the observed times.
#[derive(Debug, Clone, PartialEq)]
pub struct Reads {
    /// The observed times (phases).
    pub times: Vec<f32>,
    /// The joints read at each, in radians (and gripper units).
    pub joints: crate::data::Joints,
    /// Whether the trajectory passes through the reads (a sampled future's observations and
    /// drawn steps), so that the stage shapes only the path between them
    /// ([`crate::model::JointStage::predict_through`]); frames-only reads are the network's
    /// guesses, which the stage corrects.
    pub through: bool,
}

#[cfg(test)]
mod tests {
    use burn::tensor::{Device, Tensor};

    use super::*;

    fn spanning(span: (f32, f32)) -> Encoding {
        Encoding {
            representation: Representation::Mean(Tensor::zeros([1, 1], &Device::flex())),
            span,
            reads: None,
        }
    }

    #[test]
    fn between_observations_includes_the_first_and_the_last() {
        let encoding = spanning((0.2, 0.6));
        for (t, between) in [
            (0.2, true),
            (0.4, true),
            (0.6, true),
            (0.61, false),
            (0.1, false),
        ] {
            assert_eq!(encoding.is_between_observations(t), between, "{t}");
        }
        let none = spanning((f32::INFINITY, f32::NEG_INFINITY));
        assert!(!none.is_between_observations(0.5));
    }
}
