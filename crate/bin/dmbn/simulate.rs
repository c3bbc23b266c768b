//! `dmbn simulate`: a dataset from the simulator ([`dmbn::sim::generate`] does the work).
use std::path::PathBuf;
use std::thread;

use clap::Args;

use dmbn::data::{image_sizes_text, IMAGE_SIZES};
use dmbn::sim::{self, Action, Arm};

use crate::error::CliError;
use crate::output::progress;

#[derive(Args)]
pub struct SimulateArgs {
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
    /// The arm: ur5 (6 joints, 7 values a step) or panda (7 joints, 8 values a step).
    #[arg(long, default_value = "ur5")]
    arm: Arm,
    /// Actions to record, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "grasp,move")]
    actions: Vec<Action>,
    /// Worker threads (default: available cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    jobs: Option<u32>,
}

fn parse_image_size(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n) if IMAGE_SIZES.contains(&(n as usize)) => Ok(n),
        _ => Err(format!(
            "{s:?} is not a supported image size: expected {}",
            image_sizes_text()
        )),
    }
}

pub fn run(args: SimulateArgs) -> Result<(), CliError> {
    let (sequences, seed, image_size) = (args.sequences, args.seed, args.image_size);
    // Naming an action twice records it once.
    let mut actions = Vec::new();
    for a in args.actions {
        if !actions.contains(&a) {
            actions.push(a);
        }
    }
    let jobs = args.jobs.map_or_else(
        || thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    let bar = progress(0, "simulate");
    let result = sim::generate_with_arm(
        &args.out,
        0..sequences,
        seed,
        (args.arm, &actions),
        image_size,
        jobs,
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    let out = result?;
    let names: Vec<&str> = actions.iter().map(|a| a.name()).collect();
    println!(
        "wrote {} sequences ({sequences} per action: {}; {} arm; seeds {seed}..={}; {image_size}x{image_size} frames) to {}",
        sequences as usize * actions.len(),
        names.join(", "),
        args.arm,
        seed.wrapping_add(u64::from(sequences - 1)),
        out.display()
    );
    Ok(())
}
