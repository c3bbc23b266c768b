//! `dmbn`: generate and inspect datasets in the DMBN layout, predict, evaluate and probe models.
//! Thin on purpose: argument parsing and progress here, the work in the library. A file per
//! command; `args` and `output` hold what several share. Native only: on wasm32 (where
//! `wasm-pack test` also builds binaries) it is an empty program.
#[cfg(not(target_arch = "wasm32"))]
mod args;
#[cfg(not(target_arch = "wasm32"))]
mod calibrate;
#[cfg(not(target_arch = "wasm32"))]
mod error;
#[cfg(not(target_arch = "wasm32"))]
mod eval;
#[cfg(not(target_arch = "wasm32"))]
mod exchange;
#[cfg(not(target_arch = "wasm32"))]
mod imitate;
#[cfg(not(target_arch = "wasm32"))]
mod inspect;
#[cfg(not(target_arch = "wasm32"))]
mod output;
#[cfg(not(target_arch = "wasm32"))]
mod predict;
#[cfg(not(target_arch = "wasm32"))]
mod probe;
#[cfg(not(target_arch = "wasm32"))]
mod probe_sets;
#[cfg(not(target_arch = "wasm32"))]
mod sample;
#[cfg(not(target_arch = "wasm32"))]
mod score;
#[cfg(not(target_arch = "wasm32"))]
mod simulate;

#[cfg(not(target_arch = "wasm32"))]
#[derive(clap::Parser)]
#[command(
    name = "dmbn",
    version,
    about = "DMBN datasets and models: simulate, inspect, predict, sample, eval, probe, score, calibrate, imitate, export, import"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[cfg(not(target_arch = "wasm32"))]
#[derive(clap::Subcommand)]
enum Command {
    /// Generate a dataset with the simulator, in the DMBN layout with PNG frames.
    ///
    /// Sequence id i (0..N) of every action uses seed S + i, so a dataset is reproduced
    /// exactly from (N, S, image size). The dataset is built in `<out>.tmp-<pid>` and renamed
    /// to OUT at the end: an interrupted run leaves no partial OUT.
    Simulate(simulate::SimulateArgs),
    /// Read and validate every sequence of a dataset, then print a summary.
    Inspect(inspect::InspectArgs),
    /// Predict a whole sequence from a few observed steps with a trained model.
    ///
    /// Writes mean/<k>.png (predicted frames), sigma/<k>.png (σ heat maps, one scale for the
    /// sequence), truth/<k>.png, joints.png (true, predicted mean, ±2σ band, observed points)
    /// and scores.json (with --arrays also prediction.safetensors); prints MSE and NLL of both
    /// modalities.
    Predict(predict::PredictArgs),
    /// Draw S coherent futures of a sequence from a few observed steps (autoregressive CNP
    /// sampling): one performable joint trajectory each.
    ///
    /// The model draws the joints at --grid of the imagined steps one after another, each
    /// added to its contexts with the frame it predicts there, then decodes its mean at every
    /// step. Writes samples.csv and samples.json (every future's joints and drawn steps, the
    /// single mean, the truth, the scores), fan.png (the futures over the truth and the mean's
    /// ±2σ band) and strips.png (frames of the truth, the mean and each future); prints the
    /// energy score of the futures against the single mean's.
    Sample(sample::SampleArgs),
    /// Reconstruct a t, p or f sequence from K observations (the paper's Figures 2-3).
    ///
    /// Writes figure.png (observed, generated with σ maps, targets, joint curves) and
    /// eval.json; prints MSE and NLL over the sequence.
    Eval(eval::EvalArgs),
    /// The time-regression probe (the paper's Table 1): how well the context time can be read
    /// back from each encoder's encodings, for Null, Random, DMBN and DMBN-PTE.
    ///
    /// Writes probe.md (the table) and probe.json (every seed's MSE).
    Probe(probe::ProbeArgs),
    /// The quality benchmark: models against the trivial baselines on held-out sequences.
    ///
    /// interp: K evenly spaced observations, every step predicted; extrap: the first 30%
    /// observed at 3 steps, the rest predicted. Baselines: joints linearly interpolated between
    /// the observations (held outside them) and the nearest observation's frame — holding the
    /// last observation for extrap — and, with --mean-ids, each action's mean motion. Prints a
    /// table per scenario (joint RMSE in radians, gripper error, image MSE, errors at the
    /// observed steps, object visibility, NLL); --json writes them.
    Score(score::ScoreArgs),
    /// Scale a model file's joint σ so that mean ± 2σ holds 95% of the truth.
    ///
    /// Pools the joints' errors in units of their σ at the unobserved steps of both scenarios
    /// of `score` on --ids (ids the model did not train on) and writes the model with the
    /// factor that makes ±2σ cover 95.45% of them in its header; every prediction of the file
    /// (natively, in the page, in the PyTorch twin) applies it.
    Calibrate(calibrate::CalibrateArgs),
    /// The imitation benchmark: models see a demonstration and the simulated arm performs
    /// what they imagine.
    ///
    /// frames: K evenly spaced frames observed (no joints), the arm performs the predicted
    /// joint means; finish: the first 30% observed, performed as recorded, then the
    /// prediction. The object is placed as in the demonstration; a grasp succeeds when it
    /// lifts the object 10 cm and carries it to within 5 cm of the demonstration's spot, a
    /// push when it lands within 3 cm of it. With --samples S, each model also imagines S
    /// futures per demonstration (as `dmbn sample`), all performed: their validity and
    /// coverage beside the single mean's row.
    /// Each model against the ceiling (the recorded joints performed) and the floor (the
    /// action's mean motion performed): success rate, object and path errors, joint RMSE.
    Imitate(imitate::ImitateArgs),
    /// Write a model file's weights as safetensors for PyTorch (python/dmbn_torch).
    ///
    /// Every tensor under its PyTorch twin's name and layout (Conv2d [out, in, kh, kw],
    /// Linear [out, in], LayerNorm weight/bias); the model's kind, config and joint
    /// normalisation as the metadata entry `dmbn`.
    Export(exchange::ExportArgs),
    /// Write a model file from safetensors (from `dmbn export` or PyTorch), so that weights
    /// trained in PyTorch run natively and in the page.
    Import(exchange::ImportArgs),
}

#[cfg(not(target_arch = "wasm32"))]
fn main() -> std::process::ExitCode {
    // A closed output pipe (`| head`) ends the process quietly, as it does other tools,
    // instead of a panic in println! (Rust ignores SIGPIPE by default).
    // SAFETY: restoring a signal's default disposition before any thread is started.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = <Cli as clap::Parser>::parse();
    let result = match cli.command {
        Command::Simulate(args) => simulate::run(args),
        Command::Inspect(args) => inspect::run(args),
        Command::Predict(args) => predict::run(args),
        Command::Sample(args) => sample::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Probe(args) => probe::run(args),
        Command::Score(args) => score::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Imitate(args) => imitate::run(args),
        Command::Export(args) => exchange::export(args),
        Command::Import(args) => exchange::import(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(target_arch = "wasm32")]
fn main() {}
