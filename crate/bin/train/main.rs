//! `train`: trains DMBN, DMBN-PTE or the attentive model on a dataset in the DMBN layout. Thin on purpose:
//! argument parsing and progress here, the work in `dmbn::train`. Native only: on wasm32
//! (where `wasm-pack test` also builds binaries) it is an empty program.
#[cfg(not(target_arch = "wasm32"))]
mod cli;

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    cli::main()
}

#[cfg(target_arch = "wasm32")]
fn main() {}
