//! `train`: trains DMBN, DMBN-PTE or the attentive model on a dataset in the DMBN layout. Thin on purpose:
//! argument parsing and progress here, the work in `dmbn::train`. Native only: on wasm32
//! (where `wasm-pack test` also builds binaries) it is an empty program.
#[cfg(not(target_arch = "wasm32"))]
mod cli;

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    // A closed output pipe (`| head`) ends the process quietly, as it does other tools,
    // instead of a panic in println! (Rust ignores SIGPIPE by default).
    // SAFETY: restoring a signal's default disposition before any thread is started.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    cli::main()
}

#[cfg(target_arch = "wasm32")]
fn main() {}
