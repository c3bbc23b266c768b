//! `dmbn eval` (a t/p/f sequence reconstructed from K observations: figure, MSE, NLL) and
//! `dmbn probe` (the time-regression probe: the paper's Table 1).
use std::path::PathBuf;

use clap::Args;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;

use dmbn::augment::{EvalMode, EvalSequence};
use dmbn::eval::{evaluate, evenly_spaced, probe, HeadConfig, ProbeConfig};
use dmbn::figure::{eval_figure, save_png};
use dmbn::model::ModelKind;
use dmbn::predict::{Predictor, Scores};
use dmbn::train::Split;

use crate::cli::CliError;
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
    /// Dataset root in the DMBN layout (split by id: the last --test-fraction of ids are test).
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
    /// Fraction of the ids whose sequences are the test set.
    #[arg(long, default_value_t = 0.2)]
    test_fraction: f64,
    /// Adam steps of each regression head.
    #[arg(long, default_value_t = 1500)]
    head_steps: usize,
    /// Output folder: probe.md and probe.json.
    #[arg(long)]
    out: PathBuf,
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
    let split = Split::load(&args.data, size, args.test_fraction)?;
    if split.val.is_empty() {
        return Err(CliError::Usage(
            "the dataset has too few ids for a test split".into(),
        ));
    }
    eprintln!(
        "probe on {}: {} training and {} test sequences (test ids {:?}), {} seeds",
        args.data.display(),
        split.train.len(),
        split.val.len(),
        split.val_ids,
        args.seeds
    );
    let config = ProbeConfig {
        seeds: args.seeds,
        head: HeadConfig::new().with_steps(args.head_steps),
    };
    let report = probe(&dmbn, &pte, &split.train, &split.val, &config, |m| {
        eprintln!("  {m}")
    })?;
    create_dir(&args.out)?;
    let table = report.markdown();
    write(&args.out.join("probe.md"), table.as_bytes())?;
    write_json(&args.out.join("probe.json"), &report)?;
    print!("{table}");
    println!(
        "({} training / {} test steps, {} seeds, {:.0} s); wrote {}",
        report.train_steps,
        report.test_steps,
        report.seeds,
        report.seconds,
        args.out.display()
    );
    Ok(())
}
