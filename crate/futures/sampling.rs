use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::model::ModelError;

/// In which order the grid's target steps are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Order {
    /// Earliest first: each draw extrapolates a little from the last (the default).
    LeftToRight,
    /// A random permutation per sample (seeded).
    Random,
}

impl Order {
    /// `left-to-right` or `random`.
    pub fn name(self) -> &'static str {
        match self {
            Order::LeftToRight => "left-to-right",
            Order::Random => "random",
        }
    }
}

impl fmt::Display for Order {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Order {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "left-to-right" => Ok(Order::LeftToRight),
            "random" => Ok(Order::Random),
            _ => Err(format!(
                "{s:?} is not an order: expected left-to-right or random"
            )),
        }
    }
}

/// How a future is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The latent path's where the model has one, otherwise autoregressive (the default).
    Auto,
    /// Autoregressive: the grid's steps drawn one after another (any model).
    Ar,
    /// The model's latent path: z drawn once from its prior, then the mean at every step.
    Latent,
}

impl Method {
    /// `auto`, `ar` or `latent`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Ar => "ar",
            Method::Latent => "latent",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Method::Auto),
            "ar" => Ok(Method::Ar),
            "latent" => Ok(Method::Latent),
            _ => Err(format!(
                "{s:?} is not a method: expected auto, ar or latent"
            )),
        }
    }
}

/// How a drawn step's joint values go together (autoregressive futures).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum JointDraws {
    /// Correlated where the model file holds a [`crate::model::JointCorrelation`], otherwise
    /// independent (the default).
    Auto,
    /// As the file's correlation says (fails without one).
    Correlated,
    /// Each joint on its own, from its predicted Gaussian.
    Independent,
}

impl JointDraws {
    /// `auto`, `correlated` or `independent`.
    pub fn name(self) -> &'static str {
        match self {
            JointDraws::Auto => "auto",
            JointDraws::Correlated => "correlated",
            JointDraws::Independent => "independent",
        }
    }
}

impl fmt::Display for JointDraws {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for JointDraws {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(JointDraws::Auto),
            "correlated" => Ok(JointDraws::Correlated),
            "independent" => Ok(JointDraws::Independent),
            _ => Err(format!(
                "{s:?} is not a way to draw joints: expected auto, correlated or independent"
            )),
        }
    }
}

/// How futures are sampled ([`super::draw_futures`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sampling {
    /// S: futures drawn (as one batch of sequences).
    pub samples: usize,
    /// Autoregressive or through the model's latent path.
    pub method: Method,
    /// G: target steps drawn one after another per future, evenly spaced over the targets
    /// (the last target among them).
    pub grid: usize,
    /// The order the grid is drawn in.
    pub order: Order,
    /// A drawn step's joints: correlated as the model file says, or each on its own.
    pub joints: JointDraws,
    /// C: correlated joints vary along the C leading principal directions of the file's
    /// correlation only (`None`: all of them; [`crate::model::JointCorrelation::correlate`]).
    pub components: Option<usize>,
    /// Each autoregressive future conditions on its own bootstrap resample of the
    /// observations (drawn with replacement, the latest always kept): the network's guess at
    /// what the observations leave open shifts with the glimpses it is given, and a future
    /// per resample spreads over those guesses (Lee et al., "Bootstrapping Neural Processes",
    /// NeurIPS 2020).
    pub bootstrap: bool,
    /// Where the model file has a joint stage ([`crate::model::JointStage`]), it gives an
    /// autoregressive future's joints between the observations and the drawn steps, whatever
    /// the blend: the network alone, conditioned on them, cuts the corners between them and
    /// lands pushes short (`false`: the network's own, frames only too).
    pub stage: bool,
    /// K: autoregressive futures drawn K × S, of which the S representatives are kept
    /// ([`super::representatives`]); 1: the S drawn. Latent futures are drawn as such.
    pub oversample: usize,
    /// τ: each step (or the latent z) is drawn from N(μ, (τσ)²); below 1 the futures keep
    /// nearer the mean.
    pub temperature: f32,
    /// τ at an autoregressive future's end (its last target step), where what the
    /// observations leave open lies (how far a push goes, where a carry ends); the steps
    /// before it only shape the path there.
    pub end_temperature: f32,
    /// Seeds the draws: the same seed, the same futures, natively and in wasm.
    pub seed: u64,
}

/// The defaults were chosen on a design set no figure is reported on (seeds 1000000-1000099,
/// the page's default model finishing 100 grasps and 100 pushes from their first 30%; docs/
/// results.md, *Many futures*): 2 steps drawn (1, 3, 4 and 8 covered fewer demonstrations),
/// left to right (random orders covered fewer), correlated joints along their 2 leading
/// principal directions with τ 0.7, each future from a bootstrap resample of the
/// observations, the joint stage between the drawn steps, the future's end at τ 1 (with a
/// joint correlation per action, a wider end keeps a carry's height and covers more of both
/// actions; with one per action and drawn step, 2 directions keep it better than 3), the
/// representatives of 4 × S (docs/results.md has the figures, from four design sets).
impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            samples: 8,
            method: Method::Auto,
            grid: 2,
            order: Order::LeftToRight,
            joints: JointDraws::Auto,
            components: Some(2),
            bootstrap: true,
            stage: true,
            oversample: 4,
            temperature: 0.7,
            end_temperature: 1.0,
            seed: 0,
        }
    }
}

impl Sampling {
    /// At most this many futures (a bound on one call's memory and time).
    pub const MAX_SAMPLES: usize = 256;
    /// At most this many drawn steps per future.
    pub const MAX_GRID: usize = 64;
    /// At most this many futures drawn for S representatives.
    pub const MAX_OVERSAMPLE: usize = 16;
    /// At most this many futures drawn in all (K × S): a bound on one call's memory and time.
    pub const MAX_DRAWS: usize = 1024;

    /// The same sampling drawn from seed + `offset` (each sequence of a set its own draws).
    pub fn reseeded(&self, offset: u64) -> Sampling {
        Sampling {
            seed: self.seed.wrapping_add(offset),
            ..*self
        }
    }

    /// How the futures are drawn, in words (the reports' headings): "latent path, τ 1, seed
    /// 0", "2 steps drawn, left-to-right, τ 0.7, at the end 1, seed 0", or for `auto` both.
    pub fn describe(&self) -> String {
        let joints = match self.joints {
            JointDraws::Auto => "joints correlated where the file says",
            JointDraws::Correlated => "joints correlated",
            JointDraws::Independent => "joints independent",
        };
        let mut ar = format!("{} steps drawn, {}, {joints}", self.grid, self.order);
        if let (Some(c), JointDraws::Auto | JointDraws::Correlated) = (self.components, self.joints)
        {
            ar += &format!(" along {c} principal directions");
        }
        if self.bootstrap {
            ar += ", each from a bootstrap resample of the observations";
        }
        if self.stage {
            ar += ", the joint stage between them where the file has one";
        }
        if self.oversample > 1 {
            ar += &format!(", the representatives of {} × S", self.oversample);
        }
        let how = match self.method {
            Method::Latent => "latent path".to_string(),
            Method::Ar => ar,
            Method::Auto => format!("a model's latent path, or without one {ar}"),
        };
        let tau = match self.method {
            Method::Latent => format!("τ {}", self.temperature),
            _ => format!(
                "τ {}, at the end {}",
                self.temperature, self.end_temperature
            ),
        };
        format!("{how}, {tau}, seed {}", self.seed)
    }

    /// The same sampling without representatives: S futures as drawn (what the energy score
    /// judges; see [`super::score_futures`]).
    pub fn as_drawn(&self) -> Sampling {
        Sampling {
            oversample: 1,
            ..*self
        }
    }

    /// The sampling as drawn for a model with or without a latent path and a joint
    /// correlation: each `auto` resolved.
    pub fn resolved(&self, has_latent: bool, has_correlation: bool) -> Sampling {
        let method = match self.method {
            Method::Auto if has_latent => Method::Latent,
            Method::Auto => Method::Ar,
            other => other,
        };
        let joints = match self.joints {
            JointDraws::Auto if has_correlation => JointDraws::Correlated,
            JointDraws::Auto => JointDraws::Independent,
            other => other,
        };
        Sampling {
            method,
            joints,
            ..*self
        }
    }

    /// Fails unless 1 ≤ S ≤ [`Sampling::MAX_SAMPLES`], 0 ≤ τ ≤ 4, C ≥ 1, 1 ≤ K ≤
    /// [`Sampling::MAX_OVERSAMPLE`], K × S ≤ [`Sampling::MAX_DRAWS`] and 1 ≤ G ≤
    /// [`Sampling::MAX_GRID`].
    pub fn validate(&self) -> Result<(), ModelError> {
        if !(1..=Self::MAX_SAMPLES).contains(&self.samples) {
            return Err(ModelError::observation(
                "samples",
                format!(
                    "is {}: expected 1 to {} futures",
                    self.samples,
                    Self::MAX_SAMPLES
                ),
            ));
        }
        for (field, tau) in [
            ("temperature", self.temperature),
            ("end_temperature", self.end_temperature),
        ] {
            if !(tau.is_finite() && (0.0..=4.0).contains(&tau)) {
                return Err(ModelError::observation(
                    field,
                    format!("is {tau}: expected a factor on σ from 0 to 4"),
                ));
            }
        }
        if !(1..=Self::MAX_OVERSAMPLE).contains(&self.oversample) {
            return Err(ModelError::observation(
                "oversample",
                format!(
                    "is {}: expected 1 to {} futures drawn per future kept",
                    self.oversample,
                    Self::MAX_OVERSAMPLE
                ),
            ));
        }
        if self.samples * self.oversample > Self::MAX_DRAWS {
            return Err(ModelError::observation(
                "oversample",
                format!(
                    "is {} for {} futures: expected at most {} drawn in all",
                    self.oversample,
                    self.samples,
                    Self::MAX_DRAWS
                ),
            ));
        }
        if self.components == Some(0) {
            return Err(ModelError::observation(
                "components",
                "is 0: expected 1 or more principal directions of the joints, or all",
            ));
        }
        if !(1..=Self::MAX_GRID).contains(&self.grid) {
            return Err(ModelError::observation(
                "grid",
                format!(
                    "is {}: expected 1 to {} drawn steps a future",
                    self.grid,
                    Self::MAX_GRID
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_parse_and_bad_settings_are_named() {
        assert_eq!("random".parse::<Order>(), Ok(Order::Random));
        assert_eq!("independent".parse(), Ok(JointDraws::Independent));
        assert!("together"
            .parse::<JointDraws>()
            .unwrap_err()
            .contains("auto, correlated or independent"));
        let auto = Sampling::default();
        assert_eq!(auto.resolved(false, true).joints, JointDraws::Correlated);
        assert_eq!(auto.resolved(false, false).joints, JointDraws::Independent);
        assert!("backwards"
            .parse::<Order>()
            .unwrap_err()
            .contains("left-to-right or random"));
        let bad = Sampling {
            samples: 0,
            ..Sampling::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("samples"));
        let bad = Sampling {
            components: Some(0),
            ..Sampling::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("components"));
        let bad = Sampling {
            grid: 65,
            ..Sampling::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("grid"));
        let bad = Sampling {
            samples: 256,
            oversample: 8,
            ..Sampling::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("at most 1024"));
        Sampling::default().validate().unwrap();
    }
}
