use serde::{Deserialize, Serialize};

/// Which steps a model observes and on which it is scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Scenario {
    /// K evenly spaced observations, first and last included; every step scored.
    Interp,
    /// The first 30% observed at 3 evenly spaced steps; the rest of the action scored.
    Extrap,
}

/// The observed and the scored steps of one sequence.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScenarioSteps {
    /// Observed step indices, increasing.
    pub observed: Vec<usize>,
    /// Scored step indices, increasing.
    pub scored: Vec<usize>,
}

impl Scenario {
    /// Both scenarios.
    pub const ALL: [Scenario; 2] = [Scenario::Interp, Scenario::Extrap];

    /// Fraction of the action observed in [`Scenario::Extrap`].
    pub const EXTRAP_FRACTION: f64 = 0.3;
    /// Observations in [`Scenario::Extrap`].
    pub const EXTRAP_OBSERVATIONS: usize = 3;

    /// `interp` or `extrap`.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Interp => "interp",
            Scenario::Extrap => "extrap",
        }
    }

    /// What the baseline row stands for in this scenario.
    pub fn baseline_name(self) -> &'static str {
        match self {
            Scenario::Interp => "linear joints + nearest frame",
            Scenario::Extrap => "hold last observation",
        }
    }

    /// The steps of a `len`-step sequence, `observations` (K ≥ 2) used by `interp`. `None`
    /// when the sequence is too short for the scenario (fewer than K steps for `interp`,
    /// fewer than 5 for `extrap`).
    pub fn steps(self, len: usize, observations: usize) -> Option<ScenarioSteps> {
        match self {
            Scenario::Interp => {
                if observations < 2 || len < observations {
                    return None;
                }
                let observed = (0..observations)
                    .map(|i| {
                        (i as f64 * (len - 1) as f64 / (observations - 1) as f64).round() as usize
                    })
                    .collect();
                Some(ScenarioSteps {
                    observed,
                    scored: (0..len).collect(),
                })
            }
            Scenario::Extrap => {
                if len < 5 {
                    return None;
                }
                let last = ((Self::EXTRAP_FRACTION * (len - 1) as f64).round() as usize).max(2);
                let k = Self::EXTRAP_OBSERVATIONS;
                let observed = (0..k)
                    .map(|i| (i as f64 * last as f64 / (k - 1) as f64).round() as usize)
                    .collect();
                Some(ScenarioSteps {
                    observed,
                    scored: (last + 1..len).collect(),
                })
            }
        }
    }
}

impl std::fmt::Display for Scenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Scenario {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "interp" => Ok(Scenario::Interp),
            "extrap" => Ok(Scenario::Extrap),
            _ => Err(format!(
                "{s:?} is not a scenario: expected interp or extrap"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interp_observes_first_and_last_and_scores_every_step() {
        let s = Scenario::Interp.steps(61, 5).unwrap();
        assert_eq!(s.observed, [0, 15, 30, 45, 60]);
        assert_eq!(s.scored.len(), 61);
        assert!(Scenario::Interp.steps(4, 5).is_none());
        assert!(Scenario::Interp.steps(10, 1).is_none());
    }

    #[test]
    fn extrap_observes_the_first_30_percent_and_scores_the_rest() {
        let s = Scenario::Extrap.steps(61, 5).unwrap();
        assert_eq!(s.observed, [0, 9, 18]);
        assert_eq!(s.scored, (19..61).collect::<Vec<_>>());
        assert!(Scenario::Extrap.steps(4, 5).is_none());
        assert_eq!("extrap".parse::<Scenario>(), Ok(Scenario::Extrap));
        assert!("all".parse::<Scenario>().is_err());
    }
}
