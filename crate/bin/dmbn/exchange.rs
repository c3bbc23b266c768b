//! `dmbn export` and `dmbn import`: a model file to safetensors for PyTorch, and back.
use std::path::PathBuf;

use clap::Args;

use dmbn::model::{export_file, import_file};

use crate::error::CliError;
use crate::output::write;

#[derive(Args)]
pub struct ExportArgs {
    /// Model file (written by `train`).
    #[arg(long)]
    model: PathBuf,
    /// The safetensors file to write (replaced if it exists).
    #[arg(long)]
    out: PathBuf,
    /// Store the weights as f16 (half the size).
    #[arg(long)]
    half: bool,
}

#[derive(Args)]
pub struct ImportArgs {
    /// Safetensors file with the `dmbn` metadata (from `dmbn export` or python/dmbn_torch).
    #[arg(long)]
    from: PathBuf,
    /// The model file to write (replaced if it exists).
    #[arg(long)]
    out: PathBuf,
    /// Store the weights as f16 in the model file.
    #[arg(long)]
    half: bool,
}

pub fn export(args: ExportArgs) -> Result<(), CliError> {
    let out = export_file(&args.model, args.half)?;
    write(&args.out, &out)?;
    println!("wrote {} ({} bytes)", args.out.display(), out.len());
    Ok(())
}

pub fn import(args: ImportArgs) -> Result<(), CliError> {
    let out = import_file(&args.from, args.half)?;
    write(&args.out, &out)?;
    println!("wrote {} ({} bytes)", args.out.display(), out.len());
    Ok(())
}
