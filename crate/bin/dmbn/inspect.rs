//! `dmbn inspect`: read and validate every sequence of a dataset, then print a summary.
use std::path::PathBuf;

use clap::Args;

use dmbn::data::{joint_path, Dataset, Disk, Summary};

use crate::error::CliError;
use crate::output::progress;

#[derive(Args)]
pub struct InspectArgs {
    /// Dataset root: numeric id folders holding grasp/ and move/.
    dir: PathBuf,
    /// Camera to read: a sub-folder of that name in each sequence folder (default: the frames
    /// in the sequence folder itself).
    #[arg(long)]
    camera: Option<String>,
}

pub fn run(args: InspectArgs) -> Result<(), CliError> {
    let dataset = Dataset::open(&args.dir)?.with_camera(&Disk, args.camera.as_deref())?;
    let (width, names) = dataset.joint_width(&Disk)?;
    let first = &dataset.sequences()[0];
    let reference = joint_path(&first.dir, first.id).display().to_string();
    let bar = progress(dataset.len(), "inspect");
    let mut summary = Summary::new();
    summary.joint_names = names;
    for seq_ref in dataset.sequences() {
        let read = dataset.read(seq_ref, None).and_then(|seq| {
            Dataset::check_width(seq_ref, seq.joints.width(), width, &reference)?;
            Ok(seq)
        });
        let seq = match read {
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
