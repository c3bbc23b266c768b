//! `dmbn probe`: the time-regression probe (the paper's Table 1) of a DMBN and a DMBN-PTE.
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use dmbn::eval::{probe, HeadConfig, ProbeConfig, ProbeReport};
use dmbn::model::ModelKind;
use dmbn::predict::Predictor;

use crate::args::parse_ids;
use crate::error::CliError;
use crate::output::{create_dir, write, write_json};
use crate::probe_sets::{check_split, probe_sets, TestSet};
use dmbn::data::id_list;

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

pub fn run(args: ProbeArgs) -> Result<(), CliError> {
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
    let by = match (args.test_ids, &args.test_data) {
        (Some((a, b)), _) => TestSet::Ids(a, b),
        (None, Some(dir)) => TestSet::Data(dir),
        (None, None) => TestSet::Fraction(args.test_fraction),
    };
    let (train, test) = probe_sets(&args.data, &by, size)?;
    let mut warnings = check_split(&train, &test, &by)?;
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
            by: by.name(),
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
