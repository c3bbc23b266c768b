//! `dmbn eval` (a t/p/f sequence reconstructed from K observations: figure, MSE, NLL) and
//! `dmbn probe` (the time-regression probe: the paper's Table 1).
use std::path::{Path, PathBuf};

use clap::Args;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;

use dmbn::augment::{EvalMode, EvalSequence};
use dmbn::data::{Dataset, Sequence};
use dmbn::eval::{
    evaluate, evenly_spaced, probe, split_warnings, HeadConfig, ProbeConfig, ProbeReport,
};
use dmbn::figure::{eval_figure, save_png};
use dmbn::model::ModelKind;
use dmbn::predict::{Predictor, Scores};
use dmbn::train::Split;

use crate::cli::{parse_ids, CliError};
use crate::predict::{create_dir, load, parse_blend, parse_sequence, write, write_json};

#[derive(Args)]
pub struct EvalArgs {
    /// Model file.
    #[arg(long)]
    model: PathBuf,
    /// Dataset root in the DMBN layout.
    #[arg(long)]
    data: PathBuf,
    /// Sequence, as ID/ACTION (e.g. 38/grasp).
    #[arg(long, value_parser = parse_sequence)]
    sequence: (u32, String),
    /// t: unchanged; p: time stamps permuted; f: frozen (see --freeze).
    #[arg(long, value_parser = parse_mode)]
    mode: EvalMode,
    /// Number of observed steps, spread evenly over the sequence.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    observations: u32,
    /// Blending coefficient c: 1 = images only, 0 = joints only.
    #[arg(long, default_value_t = 0.5, value_parser = parse_blend)]
    blend: f32,
    /// For f: freeze steps FROM..TO (showing step FROM); default the whole sequence.
    #[arg(long, value_parser = parse_range)]
    freeze: Option<(usize, usize)>,
    /// Seed of the p permutation.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output folder: figure.png and eval.json.
    #[arg(long)]
    out: PathBuf,
}

fn parse_mode(s: &str) -> Result<EvalMode, String> {
    s.parse()
}

fn parse_range(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("{s:?} is not FROM:TO: expected e.g. 20:60");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let (a, b): (usize, usize) = (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?);
    if a >= b {
        return Err(format!("{s:?}: FROM must be below TO"));
    }
    Ok((a, b))
}

#[derive(Serialize)]
struct EvalReport {
    model: String,
    sequence: String,
    mode: &'static str,
    observed: Vec<usize>,
    blend: f32,
    steps: usize,
    scores: Scores,
}

pub fn run_eval(args: EvalArgs) -> Result<(), CliError> {
    let (predictor, seq) = load(&args.model, &args.data, &args.sequence)?;
    let (id, action) = &args.sequence;
    let mut rng = Pcg64::seed_from_u64(args.seed);
    let shown = EvalSequence::build(args.mode, &seq, args.freeze, &mut rng);
    let observed = evenly_spaced(seq.len(), args.observations as usize);
    let evaluation = evaluate(&predictor, args.mode, shown, observed, args.blend)?;
    create_dir(&args.out)?;
    save_png(
        &args.out.join("figure.png"),
        &eval_figure(&evaluation, 8, 2)?,
    )?;
    let report = EvalReport {
        model: predictor.model().kind().to_string(),
        sequence: format!("{id}/{action}"),
        mode: args.mode.letter(),
        observed: evaluation.observed.clone(),
        blend: args.blend,
        steps: seq.len(),
        scores: evaluation.scores,
    };
    write_json(&args.out.join("eval.json"), &report)?;
    let s = evaluation.scores;
    println!(
        "{} on {id}/{action}, {}-sequence, {} observations, blend {}",
        report.model,
        report.mode,
        report.observed.len(),
        args.blend
    );
    println!(
        "image: MSE {:.5}  NLL {:.4}\njoints: MSE {:.5}  NLL {:.4} (normalised units)",
        s.image_mse, s.image_nll, s.joint_mse, s.joint_nll
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

#[derive(Args)]
pub struct ProbeArgs {
    /// Dataset root in the DMBN layout. The heads are fitted on its training ids and tested on
    /// its last --test-fraction of ids, or on the ids of --test-ids, or (with --test-data) on
    /// another dataset.
    #[arg(long)]
    data: PathBuf,
    /// The trained DMBN model file.
    #[arg(long)]
    dmbn: PathBuf,
    /// The trained DMBN-PTE model file.
    #[arg(long)]
    pte: PathBuf,
    /// Seeds (at least 2 for a confidence interval).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=100))]
    seeds: u64,
    /// Fraction of the ids of --data (the last ones) whose sequences are the test set; the
    /// default split, when neither --test-ids nor --test-data is given.
    #[arg(long, default_value_t = 0.2, value_parser = parse_fraction)]
    test_fraction: f64,
    /// Test on the ids A to B (inclusive) of --data, e.g. 32-39 (or one id, 38); the heads are
    /// fitted on all its other ids: the paper's protocol (training ids vs held-out ids).
    #[arg(long, value_name = "A-B", value_parser = parse_ids,
          conflicts_with_all = ["test_data", "test_fraction"])]
    test_ids: Option<(u32, u32)>,
    /// Test on every sequence of this second dataset; the heads are fitted on all of --data.
    #[arg(long, value_name = "DIR", conflicts_with = "test_fraction")]
    test_data: Option<PathBuf>,
    /// Adam steps of each regression head.
    #[arg(long, default_value_t = 1500, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    head_steps: u64,
    /// Output folder: probe.md and probe.json.
    #[arg(long)]
    out: PathBuf,
}

fn parse_fraction(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(f) if f > 0.0 && f < 1.0 => Ok(f),
        _ => Err(format!(
            "{s:?}: expected a fraction strictly between 0 and 1 (e.g. 0.2)"
        )),
    }
}

/// `0-7, 9, 12-13`: ids, runs shortened.
fn id_list(ids: &[u32]) -> String {
    let mut ids = ids.to_vec();
    ids.sort_unstable();
    ids.dedup();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < ids.len() {
        let mut j = i;
        while j + 1 < ids.len() && ids[j + 1] == ids[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            ids[i].to_string()
        } else {
            format!("{}-{}", ids[i], ids[j])
        });
        i = j + 1;
    }
    if parts.is_empty() {
        "none".into()
    } else {
        parts.join(", ")
    }
}

/// One side of the probe's split: sequences, the ids they come from, and where.
struct ProbeSet {
    sequences: Vec<Sequence>,
    ids: Vec<u32>,
    data: PathBuf,
}

impl ProbeSet {
    fn steps(&self) -> usize {
        self.sequences.iter().map(Sequence::len).sum()
    }
}

#[derive(Serialize)]
struct SplitInfo {
    /// How the split was made: "test-fraction", "test-ids" or "test-data".
    by: &'static str,
    train_data: String,
    train_ids: Vec<u32>,
    test_data: String,
    test_ids: Vec<u32>,
}

#[derive(Serialize)]
struct ProbeFile<'a> {
    #[serde(flatten)]
    report: &'a ProbeReport,
    split: SplitInfo,
}

/// The dataset at `root`; errors name `flag`.
fn open(root: &Path, flag: &str) -> Result<Dataset, CliError> {
    Dataset::open(root).map_err(|e| CliError::Usage(format!("{flag}: {e}")))
}

/// The sequences of `dataset` whose id passes `keep` (frames at `size`), with their ids;
/// errors name `flag`.
fn read_all(
    dataset: &Dataset,
    size: usize,
    flag: &str,
    keep: impl Fn(u32) -> bool,
) -> Result<Vec<(u32, Sequence)>, CliError> {
    dataset
        .sequences()
        .iter()
        .filter(|r| keep(r.id))
        .map(|r| {
            let seq = dataset
                .read(r, Some(size as u32))
                .map_err(|e| CliError::Usage(format!("{flag}: {e}")))?;
            Ok((r.id, seq))
        })
        .collect()
}

fn set(seqs: Vec<(u32, Sequence)>, data: &Path) -> ProbeSet {
    let mut ids: Vec<u32> = seqs.iter().map(|(id, _)| *id).collect();
    ids.dedup();
    ProbeSet {
        sequences: seqs.into_iter().map(|(_, s)| s).collect(),
        ids,
        data: data.to_path_buf(),
    }
}

/// The training and test sets the arguments ask for, with clear errors naming the flag.
fn probe_sets(
    args: &ProbeArgs,
    size: usize,
) -> Result<(ProbeSet, ProbeSet, &'static str), CliError> {
    if let Some((a, b)) = args.test_ids {
        let dataset = open(&args.data, "--data")?;
        let ids = dataset.ids();
        let in_range = |id: u32| (a..=b).contains(&id);
        if !ids.iter().any(|&id| in_range(id)) {
            return Err(CliError::Usage(format!(
                "--test-ids {a}-{b}: {} holds no sequence with an id in {a}..={b} (its ids: {})",
                args.data.display(),
                id_list(&ids)
            )));
        }
        if ids.iter().all(|&id| in_range(id)) {
            return Err(CliError::Usage(format!(
                "--test-ids {a}-{b}: every id of {} ({}) is in the test range, none is left to \
                 fit the heads on",
                args.data.display(),
                id_list(&ids)
            )));
        }
        let train = read_all(&dataset, size, "--data", |id| !in_range(id))?;
        let test = read_all(&dataset, size, "--data", in_range)?;
        return Ok((set(train, &args.data), set(test, &args.data), "test-ids"));
    }
    if let Some(dir) = &args.test_data {
        let train = read_all(&open(&args.data, "--data")?, size, "--data", |_| true)?;
        let test = read_all(&open(dir, "--test-data")?, size, "--test-data", |_| true)?;
        return Ok((set(train, &args.data), set(test, dir), "test-data"));
    }
    let split = Split::load(&args.data, size, args.test_fraction)
        .map_err(|e| CliError::Usage(format!("--data: {e}")))?;
    if split.val.is_empty() {
        return Err(CliError::Usage(format!(
            "--test-fraction {}: {} has too few ids for a test split (at least 2 are needed; \
             or give --test-data)",
            args.test_fraction,
            args.data.display()
        )));
    }
    let ids = open(&args.data, "--data")?.ids();
    let train_ids = ids
        .into_iter()
        .filter(|id| !split.val_ids.contains(id))
        .collect();
    Ok((
        ProbeSet {
            sequences: split.train,
            ids: train_ids,
            data: args.data.clone(),
        },
        ProbeSet {
            sequences: split.val,
            ids: split.val_ids,
            data: args.data.clone(),
        },
        "test-fraction",
    ))
}

pub fn run_probe(args: ProbeArgs) -> Result<(), CliError> {
    let dmbn = Predictor::load(&args.dmbn)?;
    let pte = Predictor::load(&args.pte)?;
    for (p, kind, path) in [
        (&dmbn, ModelKind::Dmbn, &args.dmbn),
        (&pte, ModelKind::Pte, &args.pte),
    ] {
        if p.model().kind() != kind {
            return Err(CliError::Usage(format!(
                "{}: holds a {} model, expected {kind}",
                path.display(),
                p.model().kind()
            )));
        }
    }
    let size = dmbn.model().image_size();
    if pte.model().image_size() != size {
        return Err(CliError::Usage(format!(
            "the models are for different frame sizes ({size} and {})",
            pte.model().image_size()
        )));
    }
    let (train, test, by) = probe_sets(&args, size)?;
    for (side, s, flag) in [
        ("training", &train, "--data"),
        (
            "test",
            &test,
            if by == "test-data" {
                "--test-data"
            } else {
                "--data"
            },
        ),
    ] {
        if s.steps() == 0 {
            return Err(CliError::Usage(format!(
                "{flag} {}: the {side} sequences hold no steps",
                s.data.display()
            )));
        }
    }
    let mut warnings = split_warnings(train.ids.len(), train.steps(), test.ids.len(), test.steps());
    if by == "test-data" {
        let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        if same(&train.data, &test.data) {
            warnings.push(format!(
                "--test-data {} is --data: the heads are tested on the steps they were fitted \
                 on, which measures memorisation, not generalisation",
                test.data.display()
            ));
        }
    }
    eprintln!(
        "probe: fitting on {} training sequences of {} (ids {}), testing on {} sequences of {} \
         (ids {}), {} seeds",
        train.sequences.len(),
        train.data.display(),
        id_list(&train.ids),
        test.sequences.len(),
        test.data.display(),
        id_list(&test.ids),
        args.seeds
    );
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let config = ProbeConfig {
        seeds: args.seeds,
        head: HeadConfig::new().with_steps(args.head_steps as usize),
    };
    let mut report = probe(
        &dmbn,
        &pte,
        &train.sequences,
        &test.sequences,
        &config,
        |m| eprintln!("  {m}"),
    )?;
    warnings.append(&mut report.warnings);
    report.warnings = warnings;
    create_dir(&args.out)?;
    let table = report.markdown();
    write(&args.out.join("probe.md"), table.as_bytes())?;
    let file = ProbeFile {
        report: &report,
        split: SplitInfo {
            by,
            train_data: train.data.display().to_string(),
            train_ids: train.ids.clone(),
            test_data: test.data.display().to_string(),
            test_ids: test.ids.clone(),
        },
    };
    write_json(&args.out.join("probe.json"), &file)?;
    print!("{table}");
    println!(
        "({} training / {} test steps, Var(t) of the test steps {:.2} ×1e-3, {} seeds, {:.0} s); \
         wrote {}",
        report.train_steps,
        report.test_steps,
        report.test_time_variance * 1e3,
        report.seeds,
        report.seconds,
        args.out.display()
    );
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
