//! `dmbn sample`: observe a few steps of a dataset sequence, draw S coherent futures of the
//! rest (the library's `futures`), write their joints, a fan of them over the truth and a strip
//! of frames per future, and print how they score against the single mean.
use std::path::PathBuf;

use clap::Args;
use image::{imageops, RgbImage};
use serde::Serialize;

use dmbn::data::{Joints, Sequence};
use dmbn::figure::{joint_plot, save_png, JointPlot};
use dmbn::futures::{draw_futures_from, trajectories, Future, FutureScores, Method, Sampling};
use dmbn::predict::{Observations, Predictor, SequencePrediction};

use crate::args::{Observing, SamplingArgs};
use crate::error::CliError;
use crate::output::{create_dir, write, write_json};

#[derive(Args)]
pub struct SampleArgs {
    /// Every step not observed is imagined.
    #[command(flatten)]
    observing: Observing,
    /// S: futures drawn.
    #[arg(long, default_value_t = Sampling::default().samples)]
    samples: usize,
    #[command(flatten)]
    sampling: SamplingArgs,
    /// Frames in each future's strip (evenly spaced over the imagined steps).
    #[arg(long, default_value_t = 8)]
    strip: usize,
    /// Output folder (created if missing; files in it are replaced).
    #[arg(long)]
    out: PathBuf,
}

/// One future in `samples.json`.
#[derive(Serialize)]
struct FutureReport {
    /// The steps drawn, in the order drawn: phase and joint values.
    drawn: Vec<(f32, Vec<f32>)>,
    /// The future's joint means at every step.
    joints: Vec<Vec<f32>>,
}

/// What `samples.json` holds.
#[derive(Serialize)]
struct Report<'a> {
    model: String,
    sequence: String,
    observed: &'a [usize],
    blend: f32,
    sampling: Sampling,
    joint_names: &'a [String],
    times: Vec<f32>,
    imagined: &'a [usize],
    scores: FutureScores,
    truth: Vec<Vec<f32>>,
    mean: Vec<Vec<f32>>,
    futures: Vec<FutureReport>,
}

pub fn run(args: SampleArgs) -> Result<(), CliError> {
    let (predictor, seq) = args.observing.input.load()?;
    let (id, action) = &args.observing.input.sequence;
    let observations = Observations::from_sequence(&seq, &args.observing.observe)?;
    let imagined: Vec<usize> = (0..seq.len())
        .filter(|k| !args.observing.observe.contains(k))
        .collect();
    if imagined.is_empty() {
        return Err(CliError::Usage(format!(
            "--observe names every step of {id}/{action}: nothing is left to imagine"
        )));
    }
    // `auto` resolved: the report says how this model's futures were drawn.
    let has_latent = predictor.model().latent_size().is_some();
    let has_correlation = predictor.joint_correlation().is_some();
    let sampling = (args.sampling.sampling(args.samples)).resolved(has_latent, has_correlation);
    let times = seq.times();
    let future: Vec<f32> = imagined.iter().map(|&k| times[k]).collect();
    // The observations encoded once: for the futures and for the single mean.
    let observed = predictor.encode_contexts(&observations)?;
    let blend = args.observing.blend;
    let futures = draw_futures_from(&predictor, &observed, &future, blend, &sampling)?;
    let joints = trajectories(&predictor, &futures, &times)?;
    let mean = predictor.decode(&predictor.represent(&observed, blend)?, &times)?;
    let mean_joints = Joints::new(seq.joints.width(), mean.joint_mean.clone())
        .ok_or_else(|| CliError::Usage("the prediction's joints are not whole rows".into()))?;
    let scores = FutureScores::of(&joints, &mean_joints, &seq.joints, &imagined);
    let names = predictor.model().config().joint_labels();

    create_dir(&args.out)?;
    let observed = args.observing.points(&seq);
    let flat: Vec<Vec<f32>> = joints.iter().map(|j| j.values().to_vec()).collect();
    let plot = JointPlot {
        times: &times,
        truth: Some(&seq.joints),
        mean: &mean.joint_mean,
        sigma: &mean.joint_sigma,
        observed: &observed,
        samples: &flat,
        names: &names,
    };
    save_png(&args.out.join("fan.png"), &joint_plot(&plot, 900, 900)?)?;
    let strip_steps = spaced(&imagined, args.strip);
    save_png(
        &args.out.join("strips.png"),
        &strips(&predictor, &seq, &futures, &mean, &strip_steps)?,
    )?;
    write(
        &args.out.join("samples.csv"),
        csv(&names, &times, &joints, &mean_joints).as_bytes(),
    )?;
    let rows = |j: &Joints| j.rows().map(<[f32]>::to_vec).collect::<Vec<_>>();
    let report = Report {
        model: predictor.model().kind().to_string(),
        sequence: format!("{id}/{action}"),
        observed: &args.observing.observe,
        blend: args.observing.blend,
        sampling,
        joint_names: &names,
        times: times.clone(),
        imagined: &imagined,
        scores,
        truth: rows(&seq.joints),
        mean: rows(&mean_joints),
        futures: futures
            .iter()
            .zip(&joints)
            .map(|(f, j)| FutureReport {
                drawn: f.drawn.clone(),
                joints: rows(j),
            })
            .collect(),
    };
    write_json(&args.out.join("samples.json"), &report)?;
    println!(
        "{} on {id}/{action} ({} steps), observed {:?}, blend {}: {} futures ({})",
        report.model,
        seq.len(),
        args.observing.observe,
        args.observing.blend,
        sampling.samples,
        Sampling {
            grid: sampling.grid.min(imagined.len()),
            ..sampling
        }
        .describe()
    );
    // Representatives spread wider than draws: their energy score flatters them.
    let kept = if sampling.oversample > 1 && sampling.method == Method::Ar {
        " (of representatives, not draws: dmbn score judges draws)"
    } else {
        ""
    };
    println!(
        "arm joints over the {} imagined steps (rad): energy score{kept} {:.4} (the single mean's {:.4}), best of {} {:.4}, a future's RMSE {:.4}",
        imagined.len(),
        scores.energy,
        scores.energy_of_mean,
        sampling.samples,
        scores.best_rmse,
        scores.sample_rmse
    );
    println!("wrote {}", args.out.display());
    Ok(())
}

/// Up to `n` of `steps`, evenly spaced, the first and the last included.
fn spaced(steps: &[usize], n: usize) -> Vec<usize> {
    let (m, n) = (steps.len(), n.max(1));
    if m <= n {
        return steps.to_vec();
    }
    if n == 1 {
        return vec![steps[m - 1]];
    }
    (0..n).map(|i| steps[i * (m - 1) / (n - 1)]).collect()
}

/// A grid of frames at `steps`: the truth's row, the single mean's, then a row per future.
fn strips(
    predictor: &Predictor,
    seq: &Sequence,
    futures: &[Future],
    mean: &SequencePrediction,
    steps: &[usize],
) -> Result<RgbImage, CliError> {
    let s = seq.image_size;
    let times = seq.times();
    let at: Vec<f32> = steps.iter().map(|&k| times[k]).collect();
    let rows = 2 + futures.len() as u32;
    let mut out = RgbImage::from_pixel(s * steps.len() as u32, s * rows, image::Rgb([255; 3]));
    let frame = |bytes: Vec<u8>| {
        RgbImage::from_raw(s, s, bytes).ok_or_else(|| CliError::Usage("frame size".into()))
    };
    for (c, &k) in steps.iter().enumerate() {
        let x = (c as u32 * s) as i64;
        imageops::replace(&mut out, &frame(seq.frame(k).to_vec())?, x, 0);
        imageops::replace(&mut out, &frame(mean.mean_frame(k))?, x, s as i64);
    }
    for (r, future) in futures.iter().enumerate() {
        let p = predictor.decode(&future.encoding, &at)?;
        for c in 0..steps.len() {
            let (x, y) = ((c as u32 * s) as i64, ((2 + r as u32) * s) as i64);
            imageops::replace(&mut out, &frame(p.mean_frame(c))?, x, y);
        }
    }
    Ok(out)
}

/// `sample,step,time,<names>`: a row per future and step, then the single mean's (`mean`).
fn csv(names: &[String], times: &[f32], futures: &[Joints], mean: &Joints) -> String {
    let quoted: Vec<String> = names
        .iter()
        .map(|n| format!("\"{}\"", n.replace('"', "\"\"")))
        .collect();
    let mut out = format!("sample,step,time,{}\n", quoted.join(","));
    let labelled = futures
        .iter()
        .enumerate()
        .map(|(s, j)| (s.to_string(), j))
        .chain(std::iter::once(("mean".to_string(), mean)));
    for (label, joints) in labelled {
        for (k, row) in joints.rows().enumerate() {
            let values: Vec<String> = row.iter().map(f32::to_string).collect();
            out.push_str(&format!("{label},{k},{},{}\n", times[k], values.join(",")));
        }
    }
    out
}
