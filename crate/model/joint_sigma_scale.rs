use serde::{Deserialize, Serialize};

/// A calibration's factors on the predicted joint σ (`dmbn calibrate`), fitted after training
/// on sequences the model did not train on: one between the observations, one when
/// forecasting outside their span (before the first observed time or after the last), where
/// a model's error grows differently (the same factor cannot serve both: a model may be
/// over-confident between its observations and under-confident beyond them).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointSigmaScale {
    /// At target times within the span of the observed times.
    pub between: f32,
    /// At target times outside it; `None`: [`JointSigmaScale::between`].
    pub forecast: Option<f32>,
}

impl JointSigmaScale {
    /// The σ as trained.
    pub const NONE: JointSigmaScale = JointSigmaScale {
        between: 1.0,
        forecast: None,
    };

    /// The factor at a target time between the observations or, when not, outside them
    /// (see [`crate::predict::Encoding::is_between_observations`]).
    pub fn factor(&self, between_observations: bool) -> f32 {
        if between_observations {
            self.between
        } else {
            self.forecast.unwrap_or(self.between)
        }
    }

    /// Both factors multiplied by `other`'s (a calibration refitted on top of an earlier one).
    pub fn then(&self, other: JointSigmaScale) -> JointSigmaScale {
        JointSigmaScale {
            between: self.between * other.between,
            forecast: Some(
                self.forecast.unwrap_or(self.between) * other.forecast.unwrap_or(other.between),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_forecast_factor_applies_outside_the_observations_only() {
        let scale = JointSigmaScale {
            between: 1.5,
            forecast: Some(0.5),
        };
        assert_eq!(scale.factor(true), 1.5);
        assert_eq!(scale.factor(false), 0.5);
        let single = JointSigmaScale {
            between: 2.0,
            forecast: None,
        };
        assert_eq!(single.factor(false), 2.0);
        assert_eq!(JointSigmaScale::NONE.factor(false), 1.0);
        let again = single.then(scale);
        assert_eq!(again.factor(true), 3.0);
        assert_eq!(again.factor(false), 1.0);
    }
}
