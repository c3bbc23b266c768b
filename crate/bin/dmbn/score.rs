//! `dmbn score`: the quality benchmark (models against the trivial baselines on held-out
//! sequences).
use std::collections::BTreeMap;
use std::path::PathBuf;

use clap::{Args, ValueEnum};

use dmbn::data::Sequence;
use dmbn::figure::{calibration_plot, save_png};
use dmbn::futures::{score_futures, FutureScoreSums, Sampling};
use dmbn::predict::Predictor;
use dmbn::quality::{score_sequence, Accumulator, MeanMotion, QualityReport, QualityRow, Scenario};

use crate::args::{in_ids, open_for, parse_blend, parse_ids, sequences_in, SamplingArgs};
use crate::error::CliError;
use crate::output::{model_name, progress, write_json};

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum ScenarioArg {
    /// K evenly spaced observations (first and last included), every step predicted.
    Interp,
    /// The first 30% observed at 3 steps, the rest predicted.
    Extrap,
    /// Both.
    All,
}

#[derive(Args)]
pub struct ScoreArgs {
    /// Model file; repeat to compare models on the same sequences.
    #[arg(long = "model", required = true)]
    models: Vec<PathBuf>,
    /// Dataset root in the DMBN layout.
    #[arg(long)]
    data: PathBuf,
    /// Camera whose frames the models see: a sub-folder of that name in each sequence folder
    /// (default: the frames in the sequence folder itself).
    #[arg(long)]
    camera: Option<String>,
    /// Sequence ids to score, A-B inclusive (default: every id). Use ids the models never
    /// trained on.
    #[arg(long, value_parser = parse_ids)]
    ids: Option<(u32, u32)>,
    /// Observations per sequence in `interp` (K ≥ 2).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(2..))]
    observations: u32,
    /// Which scenario.
    #[arg(long, value_enum, default_value = "all")]
    scenario: ScenarioArg,
    /// Blending coefficient c: 1 = images only, 0 = joints only.
    #[arg(long, default_value_t = 0.5, value_parser = parse_blend)]
    blend: f32,
    /// Also score each action's mean motion over these ids of --data (A-B; e.g. the training
    /// ids): what a model that ignores its observations would predict.
    #[arg(long, value_parser = parse_ids)]
    mean_ids: Option<(u32, u32)>,
    /// Write the reports as JSON here (a list, one per scenario).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Sampled futures per sequence (autoregressive sampling, as `dmbn sample`): their energy
    /// score, the single mean's, best-of-S and a future's RMSE at the unobserved steps; 0:
    /// none.
    #[arg(long, default_value_t = Sampling::default().samples as u32, value_parser = clap::value_parser!(u32).range(0..=Sampling::MAX_SAMPLES as i64))]
    samples: u32,
    /// How the futures are drawn (with --samples).
    #[command(flatten)]
    sampling: SamplingArgs,
    /// Draw the models' calibration curves here (PNG): per scenario, for the joints and the
    /// moving pixels, the fraction of true values inside each central interval of the
    /// predicted Gaussian against the fraction it claims.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: ScoreArgs) -> Result<(), CliError> {
    let predictors = args
        .models
        .iter()
        .map(|path| Ok((path, Predictor::load(path)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    let models: Vec<_> = predictors.iter().map(|(p, m)| (p.as_path(), m)).collect();
    let dataset = open_for(&args.data, args.camera.as_deref(), &models)?;
    let refs = sequences_in(&dataset, &args.data, args.ids)?;
    let scenarios: Vec<Scenario> = match args.scenario {
        ScenarioArg::Interp => vec![Scenario::Interp],
        ScenarioArg::Extrap => vec![Scenario::Extrap],
        ScenarioArg::All => Scenario::ALL.to_vec(),
    };
    // Sequences and mean motions at each frame size the models need.
    // Per frame size: the sequences (with their action) and the mean motions.
    type Sequences = Vec<(String, Sequence)>;
    let mut by_size: BTreeMap<usize, (Sequences, Option<MeanMotion>)> = BTreeMap::new();
    for (_, predictor) in &predictors {
        let size = predictor.model().image_size();
        if by_size.contains_key(&size) {
            continue;
        }
        let sequences = refs
            .iter()
            .map(|r| Ok((r.action.clone(), dataset.read(r, Some(size as u32))?)))
            .collect::<Result<Vec<_>, CliError>>()?;
        let mean = match args.mean_ids {
            None => None,
            Some(range) => {
                let reference = dataset
                    .sequences()
                    .iter()
                    .filter(|s| in_ids(s.id, Some(range)))
                    .map(|r| Ok((r.action.clone(), dataset.read(r, Some(size as u32))?)))
                    .collect::<Result<Vec<_>, CliError>>()?;
                let fitted = MeanMotion::fit(reference.iter().map(|(a, s)| (a.as_str(), s)));
                Some(fitted.ok_or_else(|| {
                    CliError::Usage(format!("--mean-ids {range:?}: no sequence in that range"))
                })?)
            }
        };
        by_size.insert(size, (sequences, mean));
    }

    let observations = args.observations as usize;
    // Scored as drawn, never as representatives (`score_futures`): the report says so.
    let sampling =
        (args.samples > 0).then(|| args.sampling.sampling(args.samples as usize).as_drawn());
    let mut reports = Vec::new();
    for &scenario in &scenarios {
        let mut baseline = Accumulator::default();
        let mut mean_motion: Option<Accumulator> = None;
        let mut rows = Vec::new();
        let mut futures = Vec::new();
        for (index, (path, predictor)) in predictors.iter().enumerate() {
            let (sequences, mean) = &by_size[&predictor.model().image_size()];
            let bar = progress(sequences.len(), &format!("{scenario} {}", path.display()));
            let mut model = Accumulator::default();
            let mut sampled = FutureScoreSums::default();
            for (i, (action, seq)) in sequences.iter().enumerate() {
                let scores = score_sequence(
                    predictor,
                    seq,
                    action,
                    scenario,
                    observations,
                    args.blend,
                    mean.as_ref(),
                )?;
                let steps = scenario.steps(seq.len(), observations);
                if let (Some(sampling), Some(steps)) = (&sampling, steps) {
                    let seeded = sampling.reseeded(i as u64);
                    let observed = &steps.observed;
                    let imagined: Vec<usize> = (steps.scored.iter())
                        .filter(|k| !observed.contains(k))
                        .copied()
                        .collect();
                    let scores =
                        score_futures(predictor, seq, observed, &imagined, args.blend, &seeded)?;
                    sampled.add(&scores);
                }
                bar.inc(1);
                let Some(scores) = scores else { continue };
                model.merge(&scores.model);
                // Baselines do not depend on the model: count them once.
                if index == 0 {
                    baseline.merge(&scores.baseline);
                    if let Some(m) = &scores.mean_motion {
                        mean_motion
                            .get_or_insert_with(Accumulator::default)
                            .merge(m);
                    }
                }
            }
            bar.finish_and_clear();
            if sampling.is_some() {
                futures.push(sampled.row(&model_name(path)));
            }
            rows.push(QualityRow {
                name: model_name(path),
                model: true,
                quality: model.finish(),
            });
        }
        rows.push(QualityRow {
            name: scenario.baseline_name().to_string(),
            model: false,
            quality: baseline.finish(),
        });
        if let Some(m) = mean_motion {
            rows.push(QualityRow {
                name: "mean motion of the action".to_string(),
                model: false,
                quality: m.finish(),
            });
        }
        let report = QualityReport {
            scenario,
            observations: match scenario {
                Scenario::Interp => observations,
                Scenario::Extrap => Scenario::EXTRAP_OBSERVATIONS,
            },
            blend: args.blend,
            rows,
            futures,
            sampling,
        };
        println!("{}", report.markdown());
        reports.push(report);
    }
    if let Some(path) = &args.json {
        write_json(path, &reports)?;
        println!("wrote {}", path.display());
    }
    if let Some(path) = &args.plot {
        let height = 380 * reports.len() as u32;
        save_png(path, &calibration_plot(&reports, 900, height)?)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
