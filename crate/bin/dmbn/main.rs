//! `dmbn`: generate and inspect datasets in the DMBN layout, predict, evaluate and probe models.
//! Thin on purpose: argument parsing and progress here, the work in the library. Native
//! only: on wasm32 (where `wasm-pack test` also builds binaries) it is an empty program.
#[cfg(not(target_arch = "wasm32"))]
mod cli;
#[cfg(not(target_arch = "wasm32"))]
mod eval;
#[cfg(not(target_arch = "wasm32"))]
mod predict;
#[cfg(not(target_arch = "wasm32"))]
mod score;

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    cli::main()
}

#[cfg(target_arch = "wasm32")]
fn main() {}
