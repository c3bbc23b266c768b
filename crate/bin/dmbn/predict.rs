//! `dmbn predict`: observe a few steps of a dataset sequence, predict all of it, write the
//! figures and print the scores.
use std::path::PathBuf;

use clap::Args;
use image::RgbImage;
use serde::Serialize;

use dmbn::data::Sequence;
use dmbn::figure::{joint_plot, save_png, JointPlot};
use dmbn::predict::{prediction_arrays, Observations, Scores, SequencePrediction};

use crate::args::Observing;
use crate::error::CliError;
use crate::output::{create_dir, write, write_json};

#[derive(Args)]
pub struct PredictArgs {
    #[command(flatten)]
    observing: Observing,
    /// Output folder (created if missing; files in it are replaced).
    #[arg(long)]
    out: PathBuf,
    /// Also write prediction.safetensors: the observations and every predicted value
    /// unrounded (for python/dmbn_torch `check`, or numpy).
    #[arg(long)]
    arrays: bool,
}

/// What `scores.json` holds.
#[derive(Serialize)]
struct Report<'a> {
    model: String,
    sequence: String,
    observed: &'a [usize],
    blend: f32,
    steps: usize,
    scores: Scores,
}

pub fn run(args: PredictArgs) -> Result<(), CliError> {
    let (predictor, seq) = args.observing.input.load()?;
    let (id, action) = &args.observing.input.sequence;
    let observations = Observations::from_sequence(&seq, &args.observing.observe)?;
    let prediction = predictor.predict(&observations, &seq.times(), args.observing.blend)?;
    let scores = Scores::of(
        &prediction,
        &seq.frames,
        &seq.joints,
        predictor.normalization(),
    )
    .ok_or_else(|| CliError::Usage("prediction and sequence lengths differ".into()))?;

    let names = predictor.model().config().joint_labels();
    write_figures(&args, &seq, &prediction, &names)?;
    let report = Report {
        model: predictor.model().kind().to_string(),
        sequence: format!("{id}/{action}"),
        observed: &args.observing.observe,
        blend: args.observing.blend,
        steps: seq.len(),
        scores,
    };
    write_json(&args.out.join("scores.json"), &report)?;
    if args.arrays {
        let bytes = prediction_arrays(&observations, args.observing.blend, &prediction)?;
        write(&args.out.join("prediction.safetensors"), &bytes)?;
    }
    println!(
        "{} on {id}/{action} ({} steps), observed {:?}, blend {}",
        report.model,
        seq.len(),
        args.observing.observe,
        args.observing.blend
    );
    println!(
        "image: MSE {:.5}  NLL {:.4}\njoints: MSE {:.5}  NLL {:.4} (normalised units)",
        scores.image_mse, scores.image_nll, scores.joint_mse, scores.joint_nll
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

fn write_figures(
    args: &PredictArgs,
    seq: &Sequence,
    prediction: &SequencePrediction,
    names: &[String],
) -> Result<(), CliError> {
    let s = prediction.image_size as u32;
    for dir in ["mean", "sigma", "truth"] {
        create_dir(&args.out.join(dir))?;
    }
    let scale = prediction.max_image_sigma();
    let frame = |bytes: Vec<u8>| {
        RgbImage::from_raw(s, s, bytes).ok_or_else(|| CliError::Usage("frame size".into()))
    };
    for k in 0..prediction.len() {
        let name = format!("{k}.png");
        save_png(
            &args.out.join("mean").join(&name),
            &frame(prediction.mean_frame(k))?,
        )?;
        save_png(
            &args.out.join("sigma").join(&name),
            &frame(prediction.sigma_map(k, scale))?,
        )?;
        save_png(
            &args.out.join("truth").join(&name),
            &frame(seq.frame(k).to_vec())?,
        )?;
    }
    let times = seq.times();
    let observed = args.observing.points(seq);
    let plot = JointPlot {
        times: &times,
        truth: Some(&seq.joints),
        mean: &prediction.joint_mean,
        sigma: &prediction.joint_sigma,
        observed: &observed,
        samples: &[],
        names,
    };
    save_png(&args.out.join("joints.png"), &joint_plot(&plot, 900, 900)?)?;
    Ok(())
}
