//! The `dmbn` command line (native only).
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use thiserror::Error;

use crate::{eval, predict, score};
use dmbn::data::{DataError, Dataset, DatasetWriter, Sequence, Summary};
use dmbn::figure::FigureError;
use dmbn::model::ModelError;
use dmbn::sim::{self, Action, SimError};

#[derive(Parser)]
#[command(
    name = "dmbn",
    version,
    about = "DMBN datasets and models: simulate, inspect, predict, eval, probe, score"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate a dataset with the simulator, in the DMBN layout with PNG frames.
    ///
    /// Sequence id i (0..N) of every action uses seed S + i, so a dataset is reproduced
    /// exactly from (N, S, image size). The dataset is built in `<out>.tmp-<pid>` and renamed
    /// to OUT at the end: an interrupted run leaves no partial OUT.
    Simulate {
        /// Output folder; must not exist or be empty.
        #[arg(long)]
        out: PathBuf,
        /// Sequences per action.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        sequences: u32,
        /// Base seed: sequence i uses seed + i.
        #[arg(long)]
        seed: u64,
        /// Frame size in pixels.
        #[arg(long, default_value_t = 64, value_parser = parse_image_size)]
        image_size: u32,
        /// Actions to record, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "grasp,move")]
        actions: Vec<Action>,
        /// Worker threads (default: available cores).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
        jobs: Option<u32>,
    },
    /// Read and validate every sequence of a dataset, then print a summary.
    Inspect {
        /// Dataset root: numeric id folders holding grasp/ and move/.
        dir: PathBuf,
    },
    /// Predict a whole sequence from a few observed steps with a trained model.
    ///
    /// Writes mean/<k>.png (predicted frames), sigma/<k>.png (σ heat maps, one scale for the
    /// sequence), truth/<k>.png, joints.png (true, predicted mean, ±2σ band, observed points)
    /// and scores.json; prints MSE and NLL of both modalities.
    Predict(predict::PredictArgs),
    /// Reconstruct a t, p or f sequence from K observations (the paper's Figures 2-3).
    ///
    /// Writes figure.png (observed, generated with σ maps, targets, joint curves) and
    /// eval.json; prints MSE and NLL over the sequence.
    Eval(eval::EvalArgs),
    /// The time-regression probe (the paper's Table 1): how well the context time can be read
    /// back from each encoder's encodings, for Null, Random, DMBN and DMBN-PTE.
    ///
    /// Writes probe.md (the table) and probe.json (every seed's MSE).
    Probe(eval::ProbeArgs),
    /// The quality benchmark: models against the trivial baselines on held-out sequences.
    ///
    /// interp: K evenly spaced observations, every step predicted; extrap: the first 30%
    /// observed at 3 steps, the rest predicted. Baselines: joints linearly interpolated between
    /// the observations (held outside them) and the nearest observation's frame — holding the
    /// last observation for extrap — and, with --mean-ids, each action's mean motion. Prints a
    /// table per scenario (joint RMSE in radians, gripper error, image MSE, errors at the
    /// observed steps, object visibility, NLL); --json writes them.
    Score(score::ScoreArgs),
}

/// Everything a command can fail with; printed as `error: <message>`.
#[derive(Debug, Error)]
pub(crate) enum CliError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error("sequence {id} ({action}, seed {seed}): {source}")]
    Sim {
        id: u32,
        action: Action,
        seed: u64,
        #[source]
        source: SimError,
    },
    #[error("{0}")]
    Worker(String),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Figure(#[from] FigureError),
    #[error(transparent)]
    Train(#[from] dmbn::train::TrainError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{0}")]
    Usage(String),
}

/// An id range `A-B` (inclusive) or a single id (`--ids`, `--mean-ids`, `--test-ids`).
pub(crate) fn parse_ids(s: &str) -> Result<(u32, u32), String> {
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

pub(crate) fn parse_image_size(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n @ (64 | 128)) => Ok(n),
        _ => Err(format!(
            "{s:?} is not a supported image size: expected 64 or 128"
        )),
    }
}

pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate {
            out,
            sequences,
            seed,
            image_size,
            actions,
            jobs,
        } => {
            let mut unique = Vec::new();
            for a in actions {
                if !unique.contains(&a) {
                    unique.push(a);
                }
            }
            simulate(out, sequences, seed, image_size, &unique, jobs)
        }
        Command::Inspect { dir } => inspect(dir),
        Command::Predict(args) => predict::run(args),
        Command::Eval(args) => eval::run_eval(args),
        Command::Probe(args) => eval::run_probe(args),
        Command::Score(args) => score::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

pub(crate) fn progress(len: usize, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// One finished episode, sent from a worker to the writing thread.
type Job = (u32, Action, u64, Result<Sequence, SimError>);

fn simulate(
    out: PathBuf,
    sequences: u32,
    seed: u64,
    image_size: u32,
    actions: &[Action],
    jobs: Option<u32>,
) -> Result<(), CliError> {
    let mut writer = DatasetWriter::create(&out)?;
    let tasks: Vec<(u32, Action)> = (0..sequences)
        .flat_map(|id| actions.iter().map(move |&a| (id, a)))
        .collect();
    let workers = jobs.map_or_else(
        || thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    let workers = workers.min(tasks.len()).max(1);
    let bar = progress(tasks.len(), "simulate");
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);

    let result = thread::scope(|s| -> Result<(), CliError> {
        let (tx, rx) = mpsc::sync_channel::<Job>(workers * 2);
        for _ in 0..workers {
            let tx = tx.clone();
            let (tasks, next, stop) = (&tasks, &next, &stop);
            s.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let Some(&(id, action)) = tasks.get(next.fetch_add(1, Ordering::Relaxed))
                    else {
                        break;
                    };
                    let seed = seed.wrapping_add(u64::from(id));
                    let seq = sim::episode(action, seed, image_size);
                    if tx.send((id, action, seed, seq)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let outcome = write_all(rx, &mut writer, &bar);
        stop.store(true, Ordering::Relaxed);
        outcome
    });
    bar.finish_and_clear();
    result?;
    if writer.written() != tasks.len() {
        return Err(CliError::Worker(format!(
            "only {} of {} sequences were generated",
            writer.written(),
            tasks.len()
        )));
    }
    let written = writer.written();
    let names: Vec<&str> = actions.iter().map(|a| a.name()).collect();
    let out = writer.finish()?;
    println!(
        "wrote {written} sequences ({sequences} per action: {}; seeds {seed}..={}; {image_size}x{image_size} frames) to {}",
        names.join(", "),
        seed.wrapping_add(u64::from(sequences - 1)),
        out.display()
    );
    Ok(())
}

/// Write episodes as they arrive; returns at the first failure, dropping `rx` so workers
/// blocked on a full channel see it closed and stop.
fn write_all(
    rx: mpsc::Receiver<Job>,
    writer: &mut DatasetWriter,
    bar: &ProgressBar,
) -> Result<(), CliError> {
    for (id, action, seed, seq) in rx {
        let seq = seq.map_err(|source| CliError::Sim {
            id,
            action,
            seed,
            source,
        })?;
        writer.write(id, action.name(), &seq)?;
        bar.inc(1);
    }
    Ok(())
}

fn inspect(dir: PathBuf) -> Result<(), CliError> {
    let dataset = Dataset::open(&dir)?;
    let bar = progress(dataset.len(), "inspect");
    let mut summary = Summary::new();
    for seq_ref in dataset.sequences() {
        let seq = dataset.read(seq_ref, None);
        let seq = match seq {
            Ok(seq) => seq,
            Err(e) => {
                bar.finish_and_clear();
                return Err(e.into());
            }
        };
        summary.add(seq_ref.id, &seq_ref.action, &seq);
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!("dataset {}: valid", dataset.root().display());
    print!("{summary}");
    Ok(())
}
