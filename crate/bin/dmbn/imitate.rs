//! `dmbn imitate`: the imitation benchmark (models see a demonstration, the simulated arm
//! performs what they imagine).
use std::collections::btree_map::Entry;
use std::collections::BTreeMap;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde::Serialize;

use dmbn::data::{Dataset, Disk, Sequence, SequenceRef};
use dmbn::futures::Sampling;
use dmbn::imitate::{
    imitate, imitate_futures, mean_motion, replay, with_noise, FutureSums, FuturesReport,
    ImitateError, ImitationReport, OutcomeSums, Task,
};
use dmbn::predict::Predictor;
use dmbn::quality::MeanMotion;
use dmbn::sim::{Action, Arm, Outcome};

use crate::args::{in_ids, parse_blend, parse_ids, sequences_in, SamplingArgs};
use crate::error::CliError;
use crate::output::{model_name, progress, write_json};

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum TaskArg {
    /// K evenly spaced frames observed, no joints; the arm performs the whole prediction.
    Frames,
    /// The first 30% observed (both modalities); the arm performs it as recorded, then the
    /// prediction.
    Finish,
    /// Both.
    All,
}

#[derive(Args)]
pub struct ImitateArgs {
    /// Model file; repeat to compare models on the same demonstrations.
    #[arg(long = "model", required = true)]
    models: Vec<PathBuf>,
    /// A simulator dataset in the DMBN layout (`dmbn simulate`): the object is placed where
    /// `object_<id>.txt` has it at the first step.
    #[arg(long)]
    data: PathBuf,
    /// Sequence ids to imitate, A-B inclusive (default: every id). Use ids the models never
    /// trained on.
    #[arg(long, value_parser = parse_ids)]
    ids: Option<(u32, u32)>,
    /// Frames observed per demonstration in `frames` (K ≥ 2, evenly spaced, first and last
    /// included; default 5). `finish` always observes its first 30% at 3 steps, so with
    /// `--task finish` this is refused.
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..))]
    observations: Option<u32>,
    /// Which task.
    #[arg(long, value_enum, default_value = "all")]
    task: TaskArg,
    /// Blending coefficient c (1 = frames only); default 1 for `frames`, 0.5 for `finish`.
    #[arg(long, value_parser = parse_blend)]
    blend: Option<f32>,
    /// Fit the floor, each action's mean motion, on these ids of --data (A-B; default: the
    /// imitated ones).
    #[arg(long, value_parser = parse_ids)]
    mean_ids: Option<(u32, u32)>,
    /// Also perform the recorded joints with smooth noise of this RMSE (radians; repeat for
    /// more rows): how much error of a model's kind each action tolerates.
    #[arg(long = "noise", value_parser = parse_noise)]
    noise: Vec<f32>,
    /// Also imagine this many futures per demonstration with each model (autoregressive
    /// sampling, as `dmbn sample`) and perform every one: validity (the share that are valid
    /// actions) and coverage (the share of demonstrations one of them succeeds on).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=Sampling::MAX_SAMPLES as i64))]
    samples: Option<u32>,
    /// How the futures are drawn (with --samples).
    #[command(flatten)]
    sampling: SamplingArgs,
    /// Write the reports as JSON here (a list, one per task, with every performance's outcome).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One performance, for the JSON.
#[derive(Serialize)]
struct Performed {
    id: u32,
    trajectory: String,
    #[serde(flatten)]
    outcome: Outcome,
}

#[derive(Serialize)]
struct TaskJson {
    #[serde(flatten)]
    report: ImitationReport,
    performances: Vec<Performed>,
    /// With --samples: the sampled futures' table, and every future's outcome.
    #[serde(skip_serializing_if = "Option::is_none")]
    futures: Option<FuturesReport>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    future_performances: Vec<Performed>,
}

const CEILING: &str = "ceiling: recorded joints";
const FLOOR: &str = "floor: mean motion";

/// `--noise`: a finite RMSE in radians, 0 to 1.
fn parse_noise(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("\"{s}\": expected a joint RMSE in radians, 0 to 1")),
    }
}

pub fn run(args: ImitateArgs) -> Result<(), CliError> {
    let predictors = args
        .models
        .iter()
        .map(|path| Ok((model_name(path), Predictor::load(path)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    let dataset = Dataset::open(&args.data)?;
    let (width, _) = dataset.joint_width(&Disk)?;
    if Arm::of_width(width).is_err() {
        return Err(CliError::Usage(format!(
            "{}: {width} joint values a step: imitate performs one of the simulator's arms ({} \
             values: the angles, then the gripper) with the object where the demonstration had \
             it, so it needs the simulator's data (`dmbn simulate`) and a model trained on it",
            args.data.display(),
            Arm::widths_text()
        )));
    }
    let imitated = sequences_in(&dataset, &args.data, args.ids)?;
    let read = |refs: &[&SequenceRef], size: usize| {
        refs.iter()
            .map(|r| {
                let action: Action = r.action.parse().map_err(|e| {
                    CliError::Usage(format!(
                        "{}: {e}: imitate performs the simulator's scripted actions, so it \
                         needs the simulator's data (`dmbn simulate`)",
                        r.dir.display()
                    ))
                })?;
                Ok((r.id, action, dataset.read(r, Some(size as u32))?))
            })
            .collect::<Result<Vec<(u32, Action, Sequence)>, CliError>>()
    };
    // The demonstrations at each frame size the models need.
    let mut by_size = BTreeMap::new();
    for (_, p) in &predictors {
        let size = p.model().image_size();
        if let Entry::Vacant(entry) = by_size.entry(size) {
            entry.insert(read(&imitated, size)?);
        }
    }
    let demos = by_size.values().next().expect("at least one model");
    let fitted;
    let reference = match args.mean_ids {
        Some(range) => {
            let refs: Vec<_> = dataset
                .sequences()
                .iter()
                .filter(|s| in_ids(s.id, Some(range)))
                .collect();
            fitted = read(&refs, demos[0].2.image_size as usize)?;
            &fitted
        }
        None => demos,
    };
    let mean =
        MeanMotion::fit(reference.iter().map(|(_, a, s)| (a.name(), s))).ok_or_else(|| {
            CliError::Usage(format!(
                "--mean-ids {:?}: no sequence in that range",
                args.mean_ids.unwrap_or_default()
            ))
        })?;

    let tasks = match args.task {
        TaskArg::Frames => vec![Task::Frames],
        TaskArg::Finish => vec![Task::Finish],
        TaskArg::All => Task::ALL.to_vec(),
    };
    if let (TaskArg::Finish, Some(k)) = (args.task, args.observations) {
        return Err(CliError::Usage(format!(
            "--observations {k}: the finish task observes the first 30% of each demonstration at \
             3 steps; --observations sets the frames task's evenly spaced frames"
        )));
    }
    let k = args.observations.unwrap_or(5) as usize;
    // Rows: the ceiling, the floor, the noisy replays, then the models in order.
    let names: Vec<String> = [CEILING.to_string(), FLOOR.to_string()]
        .into_iter()
        .chain(
            args.noise
                .iter()
                .map(|n| format!("recorded joints + {n} rad noise")),
        )
        .chain(predictors.iter().map(|(name, _)| name.clone()))
        .collect();
    let row_name = |r: usize| names[r].as_str();
    let mut out = Vec::new();
    for task in tasks {
        let blend = args.blend.unwrap_or(task.default_blend());
        // Per action, per row (in `names`' order).
        let mut sums: BTreeMap<Action, Vec<OutcomeSums>> = BTreeMap::new();
        let mut performances = Vec::new();
        // With --samples: per action, per model.
        let mut future_sums: BTreeMap<Action, Vec<FutureSums>> = BTreeMap::new();
        let mut future_performances = Vec::new();
        let sampling = args.samples.map(|s| args.sampling.sampling(s as usize));
        let rows = names.len();
        let bar = progress(demos.len() * rows, &format!("{task}"));
        for (i, (id, action, demo)) in demos.iter().enumerate() {
            // Which demonstration failed, for a message that names it.
            let named = |e: ImitateError| {
                CliError::Usage(format!("{}: {id}/{action}: {e}", args.data.display()))
            };
            let mut performed = vec![Some(replay(demo, *action).map_err(named)?)];
            performed.push(mean_motion(demo, *action, task, k, &mean).map_err(named)?);
            for &rmse in &args.noise {
                let seed = u64::from(*id);
                performed.push(with_noise(demo, *action, task, k, rmse, seed).map_err(named)?);
            }
            bar.inc(2 + args.noise.len() as u64);
            let mut futures = Vec::new();
            for (_, p) in &predictors {
                let demo = &by_size[&p.model().image_size()][i].2;
                performed.push(imitate(p, demo, *action, task, k, blend).map_err(named)?);
                if let Some(sampling) = &sampling {
                    let seeded = sampling.reseeded(u64::from(*id));
                    let f = imitate_futures(p, demo, *action, task, k, blend, &seeded);
                    futures.push(f.map_err(named)?);
                }
                bar.inc(1);
            }
            if performed.iter().any(Option::is_none) || futures.iter().any(Option::is_none) {
                continue; // too short for the task
            }
            if sampling.is_some() {
                let entry = future_sums
                    .entry(*action)
                    .or_insert_with(|| vec![FutureSums::default(); predictors.len()]);
                let models = performed.len() - predictors.len();
                for (m, f) in futures.iter().flatten().enumerate() {
                    let mean = performed[models + m].as_ref().expect("checked above");
                    entry[m].add(f, mean);
                    for (s, future) in f.iter().enumerate() {
                        future_performances.push(Performed {
                            id: *id,
                            trajectory: format!("{} future {s}", predictors[m].0),
                            outcome: future.outcome,
                        });
                    }
                }
            }
            let entry = sums
                .entry(*action)
                .or_insert_with(|| vec![OutcomeSums::default(); rows]);
            for (r, imitation) in performed.iter().flatten().enumerate() {
                entry[r].add(imitation);
                performances.push(Performed {
                    id: *id,
                    trajectory: row_name(r).to_string(),
                    outcome: imitation.outcome,
                });
            }
        }
        bar.finish_and_clear();
        let mut report = ImitationReport {
            task,
            observations: k,
            blend,
            rows: Vec::new(),
        };
        for (action, rows) in &sums {
            for (r, s) in rows.iter().enumerate() {
                let ceiling = (r > 0).then_some(&rows[0]);
                report.rows.push(s.row(row_name(r), action.name(), ceiling));
            }
        }
        println!("{}", report.table());
        let futures = sampling.map(|sampling| {
            let mut futures = FuturesReport {
                task,
                sampling,
                rows: Vec::new(),
            };
            for (action, rows) in &future_sums {
                let ceiling = sums[action][0]
                    .row(CEILING, action.name(), None)
                    .success_rate;
                for (m, s) in rows.iter().enumerate() {
                    let name = &predictors[m].0;
                    futures.rows.push(s.row(name, action.name(), Some(ceiling)));
                }
            }
            println!("{}", futures.table());
            futures
        });
        out.push(TaskJson {
            report,
            performances,
            futures,
            future_performances,
        });
    }
    if let Some(path) = &args.json {
        write_json(path, &out)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
