//! `dmbn inspect`: read and validate every sequence of a dataset, then print a summary.
use std::path::PathBuf;

use clap::Args;

use dmbn::data::{Dataset, Summary};

use crate::error::CliError;
use crate::output::progress;

#[derive(Args)]
pub struct InspectArgs {
    /// Dataset root: numeric id folders holding grasp/ and move/.
    dir: PathBuf,
}

pub fn run(args: InspectArgs) -> Result<(), CliError> {
    let dataset = Dataset::open(&args.dir)?;
    let bar = progress(dataset.len(), "inspect");
    let mut summary = Summary::new();
    for seq_ref in dataset.sequences() {
        let seq = match dataset.read(seq_ref, None) {
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
