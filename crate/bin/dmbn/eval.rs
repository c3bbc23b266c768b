//! `dmbn eval`: a t/p/f sequence reconstructed from K observations (figure, MSE, NLL).
use std::path::PathBuf;

use clap::Args;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;

use dmbn::augment::{EvalMode, EvalSequence};
use dmbn::eval::{evaluate, evenly_spaced};
use dmbn::figure::{eval_figure, save_png};
use dmbn::predict::Scores;

use crate::args::{parse_blend, ModelAndSequence};
use crate::error::CliError;
use crate::output::{create_dir, write_json};

#[derive(Args)]
pub struct EvalArgs {
    #[command(flatten)]
    input: ModelAndSequence,
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
        .map_err(|e: dmbn::augment::AugmentError| e.to_string())
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

pub fn run(args: EvalArgs) -> Result<(), CliError> {
    let (predictor, seq) = args.input.load()?;
    let (id, action) = &args.input.sequence;
    let mut rng = Pcg64::seed_from_u64(args.seed);
    let shown = EvalSequence::build(args.mode, &seq, args.freeze, &mut rng);
    let observed = evenly_spaced(seq.len(), args.observations as usize);
    let evaluation = evaluate(&predictor, args.mode, shown, observed, args.blend)?;
    create_dir(&args.out)?;
    save_png(
        &args.out.join("figure.png"),
        &eval_figure(
            &evaluation,
            &predictor.model().config().joint_labels(),
            8,
            2,
        )?,
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
