//! `train`: trains DMBN, DMBN-PTE or the attentive model on a dataset in the DMBN layout, and
//! fits a joint stage to it. Thin on purpose: the flags (`args.rs`), training the network
//! (`train.rs`) and fitting the joint stage (`joint_stage.rs`) with their progress here, the
//! work in `dmbn::train`. Native only: on wasm32 (where `wasm-pack test` also builds binaries)
//! it is an empty program.
#[cfg(not(target_arch = "wasm32"))]
mod args;
#[cfg(not(target_arch = "wasm32"))]
mod joint_stage;
#[cfg(not(target_arch = "wasm32"))]
mod train;

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    use clap::Parser;

    // A closed output pipe (`| head`) ends the process quietly, as it does other tools,
    // instead of a panic in println! (Rust ignores SIGPIPE by default).
    // SAFETY: restoring a signal's default disposition before any thread is started.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    match run(args::Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Trains the network unless `--init FILE --steps 0 --joint-stage` asks for a stage alone,
/// then fits the joint stage if asked.
#[cfg(not(target_arch = "wasm32"))]
fn run(args: args::Args) -> Result<(), dmbn::train::TrainError> {
    if args.joint_stage {
        joint_stage::settings(&args).validate()?;
        if args.steps == Some(0) {
            return joint_stage::add_to_init_file(&args);
        }
    }
    let (trainer, path) = train::train(&args)?;
    if args.joint_stage {
        joint_stage::add_after_training(&args, &trainer, &path)?;
    }
    train::report(&trainer, &path);
    Ok(())
}

#[cfg(target_arch = "wasm32")]
fn main() {}
