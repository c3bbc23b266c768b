//! What several commands take: parsers for their shared arguments, and the model and
//! sequence that `--model`, `--data` and `--sequence` name.
use std::path::{Path, PathBuf};

use clap::Args;

use dmbn::data::{Dataset, Disk, Sequence, SequenceRef};
use dmbn::futures::{JointDraws, Method, Order, Sampling};
use dmbn::predict::Predictor;

use crate::error::CliError;

/// An id range `A-B` (inclusive) or a single id (`--ids`, `--mean-ids`, `--test-ids`).
pub fn parse_ids(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{s:?} is not an id range A-B: expected e.g. 32-39 (or one id, 38)");
    let id = |v: &str| v.trim().parse::<u32>().map_err(|_| bad());
    let (a, b) = match s.split_once('-') {
        Some((a, b)) => (id(a)?, id(b)?),
        None => {
            let a = id(s)?;
            (a, a)
        }
    };
    if a > b {
        return Err(format!("{s:?}: A ({a}) must not exceed B ({b})"));
    }
    Ok((a, b))
}

/// Whether `id` lies in the range `ids` (every id without one).
pub fn in_ids(id: u32, ids: Option<(u32, u32)>) -> bool {
    ids.is_none_or(|(a, b)| (a..=b).contains(&id))
}

/// The sequences of `dataset` (opened from `data`) whose ids lie in `ids` (`--ids`); an error
/// naming the folder and the range when there is none.
pub fn sequences_in<'a>(
    dataset: &'a Dataset,
    data: &Path,
    ids: Option<(u32, u32)>,
) -> Result<Vec<&'a SequenceRef>, CliError> {
    let refs: Vec<_> = dataset
        .sequences()
        .iter()
        .filter(|s| in_ids(s.id, ids))
        .collect();
    if refs.is_empty() {
        let (a, b) = ids.unwrap_or_default();
        return Err(CliError::Usage(format!(
            "{}: no sequence with an id in {a}-{b}",
            data.display()
        )));
    }
    Ok(refs)
}

/// The dataset at `data`, its `camera`'s frames (`--camera`; the default camera without),
/// refused with both counts unless its sequences have as many joint values a step as each of
/// `models` (path, predictor) reads.
pub fn open_for(
    data: &Path,
    camera: Option<&str>,
    models: &[(&Path, &Predictor)],
) -> Result<Dataset, CliError> {
    let dataset = Dataset::open(data)?.with_camera(&Disk, camera)?;
    let (width, _) = dataset.joint_width(&Disk)?;
    for (path, predictor) in models {
        if predictor.joint_count() != width {
            return Err(CliError::Usage(format!(
                "{}: the model reads {} joint values a step, but the data at {} has {width}: use a model trained on this robot's data",
                path.display(),
                predictor.joint_count(),
                data.display()
            )));
        }
    }
    Ok(dataset)
}

/// A sequence as `ID/ACTION` (`--sequence`).
pub fn parse_sequence(s: &str) -> Result<(u32, String), String> {
    let bad = || format!("{s:?} is not ID/ACTION: expected e.g. 3/grasp");
    let (id, action) = s.split_once('/').ok_or_else(bad)?;
    let id = id.parse().map_err(|_| bad())?;
    if action.is_empty() {
        return Err(bad());
    }
    Ok((id, action.to_string()))
}

/// The blending coefficient c in [0, 1] (`--blend`).
pub fn parse_blend(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(c) if (0.0..=1.0).contains(&c) => Ok(c),
        _ => Err(format!(
            "{s:?} is not a blending coefficient: expected a number in [0, 1]"
        )),
    }
}

/// A model and one sequence of a dataset (`predict`, `eval`).
#[derive(Args)]
pub struct ModelAndSequence {
    /// Model file (written by `train`).
    #[arg(long)]
    pub model: PathBuf,
    /// Dataset root in the DMBN layout.
    #[arg(long)]
    pub data: PathBuf,
    /// Sequence, as ID/ACTION (e.g. 38/grasp).
    #[arg(long, value_parser = parse_sequence)]
    pub sequence: (u32, String),
    /// Camera whose frames the model sees: a sub-folder of that name in each sequence folder
    /// (default: the frames in the sequence folder itself).
    #[arg(long)]
    pub camera: Option<String>,
}

impl ModelAndSequence {
    /// The model and the sequence, read at the model's frame size.
    pub fn load(&self) -> Result<(Predictor, Sequence), CliError> {
        let predictor = Predictor::load(&self.model)?;
        let models = [(self.model.as_path(), &predictor)];
        let dataset = open_for(&self.data, self.camera.as_deref(), &models)?;
        let size = predictor.model().image_size() as u32;
        let (id, action) = &self.sequence;
        let seq = dataset.read(dataset.find(*id, action)?, Some(size))?;
        Ok((predictor, seq))
    }
}

/// A model, one sequence, the steps it observes and the blend (`predict`, `sample`).
#[derive(Args)]
pub struct Observing {
    #[command(flatten)]
    pub input: ModelAndSequence,
    /// Observed steps (context), comma separated step indices.
    #[arg(long, value_delimiter = ',', required = true)]
    pub observe: Vec<usize>,
    /// Blending coefficient c: 1 = images only, 0 = joints only, 0.5 = both.
    #[arg(long, default_value_t = 0.5, value_parser = parse_blend)]
    pub blend: f32,
}

impl Observing {
    /// The observed steps of `seq` as a joint plot marks them: (phase, joint values).
    pub fn points(&self, seq: &Sequence) -> Vec<(f32, Vec<f32>)> {
        let times = seq.times();
        let rows = self.observe.iter();
        rows.map(|&k| (times[k], seq.joints[k].to_vec())).collect()
    }
}

/// How sampled futures are drawn, but for their number (`sample`, `score`, `imitate`).
#[derive(Args)]
pub struct SamplingArgs {
    /// How a future is drawn: through the model's latent path (`latent`), autoregressively
    /// (`ar`), or `auto` (the latent path where the model has one).
    #[arg(long, default_value_t = Sampling::default().method)]
    pub method: Method,
    /// Steps drawn one after another per future, evenly spaced over the imagined steps.
    #[arg(long, default_value_t = Sampling::default().grid)]
    pub grid: usize,
    /// The order the grid is drawn in: left-to-right or random.
    #[arg(long, default_value_t = Sampling::default().order)]
    pub order: Order,
    /// A drawn step's joints: `correlated` as the model file's joint correlation says (fitted
    /// by `dmbn calibrate`), `independent`, or `auto` (correlated where the file holds one).
    #[arg(long, default_value_t = Sampling::default().joints)]
    pub joints: JointDraws,
    /// C: correlated joints vary along the C leading principal directions of the file's joint
    /// correlation only, or along `all` of them.
    #[arg(long, default_value_t = Components(Sampling::default().components))]
    pub components: Components,
    /// Each autoregressive future conditions on its own bootstrap resample of the
    /// observations (the latest always kept), or on all of them (`false`).
    #[arg(long, default_value_t = Sampling::default().bootstrap, action = clap::ArgAction::Set)]
    pub bootstrap: bool,
    /// Where the model file has a joint stage, it gives an autoregressive future's joints
    /// between the observations and the drawn steps, whatever the blend (`false`: the
    /// network's own).
    #[arg(long, default_value_t = Sampling::default().stage, action = clap::ArgAction::Set)]
    pub stage: bool,
    /// K: draw K × S autoregressive futures and keep their S representatives (k-means over
    /// the drawn steps), so that the S spread over what may happen; 1: the S drawn.
    #[arg(long, default_value_t = Sampling::default().oversample)]
    pub oversample: usize,
    /// τ: each drawn step's σ is multiplied by this (below 1: futures nearer the mean).
    #[arg(long, default_value_t = Sampling::default().temperature)]
    pub temperature: f32,
    /// τ at an autoregressive future's end (its last drawn step): where what the observations
    /// leave open lies, drawn wider than the path there.
    #[arg(long, default_value_t = Sampling::default().end_temperature)]
    pub end_temperature: f32,
    /// Seeds the draws (the same seed, the same futures; `score` and `imitate` draw sequence
    /// i's, or demonstration id i's, from seed + i).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

impl SamplingArgs {
    /// `samples` futures drawn so.
    pub fn sampling(&self, samples: usize) -> Sampling {
        Sampling {
            samples,
            method: self.method,
            grid: self.grid,
            order: self.order,
            joints: self.joints,
            components: self.components.0,
            bootstrap: self.bootstrap,
            stage: self.stage,
            oversample: self.oversample,
            temperature: self.temperature,
            end_temperature: self.end_temperature,
            seed: self.seed,
        }
    }
}

/// `--components`: a count of principal directions, or `all` (`None`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Components(pub std::option::Option<usize>);

impl std::str::FromStr for Components {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "all" => Ok(Components(None)),
            _ => match s.parse::<usize>() {
                Ok(c) if c >= 1 => Ok(Components(Some(c))),
                _ => Err(format!(
                    "{s:?} is not a count of principal directions: expected 1 or more, or all"
                )),
            },
        }
    }
}

impl std::fmt::Display for Components {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(c) => write!(f, "{c}"),
            None => f.write_str("all"),
        }
    }
}
