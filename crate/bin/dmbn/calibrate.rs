//! `dmbn calibrate`: a model file's joint σ scaled so that mean ± 2σ holds about 95% of the
//! truth on sequences it did not train on, between the observations and beyond them; and how
//! a step's joint errors go together there, for sampled futures.
use std::path::PathBuf;

use clap::{Args, ValueEnum};

use dmbn::data::{Dataset, SequenceRef};
use dmbn::futures::{drawn_step_errors, Sampling};
use dmbn::model::{
    with_joint_correlation, with_joint_sigma_scale, JointCorrelation, JointSigmaScale,
};
use dmbn::predict::Predictor;
use dmbn::quality::{joint_z_scores, two_sigma_scale, JointZScores, Scenario, TWO_SIGMA};

use crate::args::{open_for, parse_blend, parse_ids, sequences_in};
use crate::error::CliError;
use crate::output::{progress, write};

#[derive(Args)]
pub struct CalibrateArgs {
    /// The model file.
    #[arg(long)]
    model: PathBuf,
    /// Dataset root in the DMBN layout.
    #[arg(long)]
    data: PathBuf,
    /// Camera whose frames the models see: a sub-folder of that name in each sequence folder
    /// (default: the frames in the sequence folder itself).
    #[arg(long)]
    camera: Option<String>,
    /// Sequence ids to fit on, A-B inclusive: ids the model never trained on (its validation
    /// ids), not the ones it will be judged on.
    #[arg(long, value_parser = parse_ids)]
    ids: (u32, u32),
    /// Observations per sequence in `interp` (the quality benchmark's K).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(2..))]
    observations: u32,
    /// Blending coefficient c: 1 = images only, 0 = joints only.
    #[arg(long, default_value_t = 0.5, value_parser = parse_blend)]
    blend: f32,
    /// What to fit: the joint σ scales, the joint correlation sampled futures draw with
    /// (the errors at the steps they draw, finishing each sequence from its first 30%), or
    /// both. What is not fitted is kept as the file has it.
    #[arg(long, value_enum, default_value_t = Fit::Both)]
    fit: Fit,
    /// Where the joint correlation is fitted per region of the poses the futures' drawn steps
    /// reach, so that a draw moves the arm as the demonstrations do there (a push along the
    /// table, a carry at its height): `steps`, a region per action folder and drawn step (a
    /// draw takes, among the regions of its step, the action's whose mean pose is nearest its
    /// own: a carry's end varies where it ends, a step before mostly when it gets there);
    /// `actions`, a region per action folder over all drawn steps; K, the K k-means clusters
    /// of the poses; 1, one correlation pooled over all of them.
    #[arg(long, default_value = "steps", value_parser = parse_regions)]
    regions: Regions,
    /// Where to write the calibrated model file (the same weights, the scale in its header).
    #[arg(long)]
    out: PathBuf,
}

/// `--regions`: the joint correlation's regions.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Regions {
    Steps,
    Actions,
    Clusters(usize),
}

fn parse_regions(s: &str) -> Result<Regions, String> {
    match s {
        "steps" => Ok(Regions::Steps),
        "actions" => Ok(Regions::Actions),
        _ => match s.parse::<usize>() {
            Ok(k) if (1..=JointCorrelation::MAX_REGIONS).contains(&k) => Ok(Regions::Clusters(k)),
            _ => Err(format!(
                "{s:?}: expected steps, actions, or a count of regions from 1 to {}",
                JointCorrelation::MAX_REGIONS
            )),
        },
    }
}

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum Fit {
    Both,
    Sigma,
    Correlation,
}

/// Fits what `--fit` names on the ids and writes the file with it.
pub fn run(args: CalibrateArgs) -> Result<(), CliError> {
    let predictor = Predictor::load(&args.model)?;
    let sigma = args.fit != Fit::Correlation;
    if sigma && predictor.model().joint_stage().is_some() && args.blend == 1.0 {
        return Err(CliError::Usage(format!(
            "{}: --blend 1: this file's joint stage answers frames-only predictions between the \
             observations with its own σ (fitted with the stage), which the scales do not touch; \
             calibrate the network's σ at a blend below 1",
            args.model.display()
        )));
    }
    let mut bytes = std::fs::read(&args.model).map_err(|source| CliError::Io {
        path: args.model.clone(),
        source,
    })?;
    let models = [(args.model.as_path(), &predictor)];
    let dataset = open_for(&args.data, args.camera.as_deref(), &models)?;
    let refs = sequences_in(&dataset, &args.data, Some(args.ids))?;
    if sigma {
        bytes = fit_sigma(&args, &predictor, &dataset, &refs, &bytes)?;
    }
    if args.fit != Fit::Sigma {
        bytes = fit_correlation(&args, &predictor, &dataset, &refs, &bytes)?;
    }
    write(&args.out, &bytes)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// `bytes` with σ scales fitted on `refs`: the joints' standardised errors of both scenarios
/// of the quality benchmark pooled, and σ scaled so that ±2σ covers 95.45% of them, apart
/// between the observations and outside their span (forecasting), where a model errs
/// differently.
fn fit_sigma(
    args: &CalibrateArgs,
    predictor: &Predictor,
    dataset: &Dataset,
    refs: &[&SequenceRef],
    bytes: &[u8],
) -> Result<Vec<u8>, CliError> {
    let (a, b) = args.ids;
    let size = predictor.model().image_size() as u32;
    let bar = progress(refs.len(), "calibrating σ");
    let mut z = JointZScores::default();
    for r in refs {
        let seq = dataset.read(r, Some(size))?;
        for scenario in Scenario::ALL {
            let observations = args.observations as usize;
            z.extend(joint_z_scores(
                predictor,
                &seq,
                scenario,
                observations,
                args.blend,
            )?);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let held = |z: &[f64]| z.iter().filter(|&&v| v <= 2.0).count() as f64 / z.len() as f64;
    let factor = |z: &[f64]| two_sigma_scale(z.to_vec()).filter(|f| f.is_finite() && *f > 0.0);
    let between = factor(&z.between).ok_or_else(|| {
        CliError::Usage(format!(
            "ids {a}-{b}: no scored joint value to fit on (sequences too short?)"
        ))
    })?;
    let forecast = factor(&z.forecast);
    let scale = predictor.joint_sigma_scale().then(JointSigmaScale {
        between: between as f32,
        forecast: forecast.map(|f| f as f32),
    });
    println!(
        "joint σ × {between:.3} between the observations: ±2σ held {:.1}% of the joints on ids {a}-{b}, now {:.1}%",
        100.0 * held(&z.between),
        100.0 * TWO_SIGMA
    );
    if let Some(forecast) = forecast {
        println!(
            "joint σ × {forecast:.3} outside them (forecasting): ±2σ held {:.1}%, now {:.1}%",
            100.0 * held(&z.forecast),
            100.0 * TWO_SIGMA
        );
    }
    println!(
        "the file's scales: {:.3} between, {:.3} outside",
        scale.between,
        scale.forecast.unwrap_or(scale.between)
    );
    Ok(with_joint_sigma_scale(bytes, scale)?)
}

/// `bytes` with the joint correlation of the steps sampled futures draw (the default grid,
/// each sequence finished from its first 30%, as `dmbn imitate --task finish`) on `refs`.
fn fit_correlation(
    args: &CalibrateArgs,
    predictor: &Predictor,
    dataset: &Dataset,
    refs: &[&SequenceRef],
    bytes: &[u8],
) -> Result<Vec<u8>, CliError> {
    let (a, b) = args.ids;
    let size = predictor.model().image_size() as u32;
    let grid = Sampling::default().grid;
    let bar = progress(refs.len(), "fitting the joint correlation");
    let (mut errors, mut poses, mut actions) = (Vec::new(), Vec::new(), Vec::new());
    let (mut steps_of, mut phases) = (Vec::new(), Vec::new());
    for r in refs {
        let seq = dataset.read(r, Some(size))?;
        let Some(steps) = Scenario::Extrap.steps(seq.len(), Scenario::EXTRAP_OBSERVATIONS) else {
            continue;
        };
        let imagined: Vec<usize> = (steps.scored.iter())
            .filter(|k| !steps.observed.contains(k))
            .copied()
            .collect();
        let rows = drawn_step_errors(
            predictor,
            &seq,
            &steps.observed,
            &imagined,
            args.blend,
            grid,
        )?;
        for row in rows {
            errors.push(row.error);
            poses.push(row.pose);
            steps_of.push(row.step);
            phases.push(row.phase);
            actions.push(r.action.as_str());
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let d = predictor.joint_count();
    let mut names: Vec<&str> = actions.clone();
    names.sort_unstable();
    names.dedup();
    let action_of = |a: &&str| names.iter().position(|n| n == a).unwrap_or(0);
    let fitted = match args.regions {
        Regions::Steps => {
            let labels: Vec<usize> = (actions.iter().zip(&steps_of))
                .map(|(a, &k)| action_of(a) * grid + k)
                .collect();
            JointCorrelation::fit_labelled(&errors, &poses, &labels, Some(&phases), d)
        }
        Regions::Actions => {
            let labels: Vec<usize> = actions.iter().map(action_of).collect();
            JointCorrelation::fit_labelled(&errors, &poses, &labels, None, d)
        }
        Regions::Clusters(k) => JointCorrelation::fit_regions(&errors, &poses, d, k),
    };
    let correlation = fitted.ok_or_else(|| {
        CliError::Usage(format!(
            "ids {a}-{b}: {} drawn steps to fit the joint correlation on, {}: expected 2 or more in each region (fewer --regions, or more ids)",
            errors.len(),
            match args.regions {
                Regions::Steps => format!(
                    "a region per action and drawn step ({} × {grid})",
                    names.join(", ")
                ),
                Regions::Actions => format!("a region per action ({})", names.join(", ")),
                Regions::Clusters(k) => format!("in {k} regions"),
            }
        ))
    })?;
    let k = correlation.regions();
    // The strongest correlation of each region's R, and which actions each region holds:
    // what the regions split (they know no labels).
    let strongest = |r: &[f32]| {
        let (i, j) = (0..d * d)
            .filter(|k| k / d != k % d)
            .max_by(|&x, &y| r[x].abs().total_cmp(&r[y].abs()))
            .map_or((0, 0), |k| (k / d, k % d));
        format!(
            "strongest r = {:.2} (joint values {i} and {j})",
            r[i * d + j]
        )
    };
    println!(
        "joint correlation of sampled futures' drawn steps: {} steps of {} sequences on ids {a}-{b} ({grid} a future, blend {}); {}",
        errors.len(),
        refs.len(),
        args.blend,
        match k {
            1 => strongest(correlation.region_values(0)),
            _ => format!("{k} regions"),
        }
    );
    if k > 1 {
        let taken: Vec<usize> = (poses.iter().zip(&phases))
            .map(|(p, &t)| correlation.region_of(p, t))
            .collect();
        let region_phases = correlation.phases();
        for region in 0..k {
            let mut count: Vec<(&str, usize)> = Vec::new();
            for (&r, &action) in taken.iter().zip(&actions) {
                if r == region {
                    match count.iter_mut().find(|(a, _)| *a == action) {
                        Some((_, n)) => *n += 1,
                        None => count.push((action, 1)),
                    }
                }
            }
            let steps: usize = count.iter().map(|(_, n)| n).sum();
            let count: Vec<String> = count.iter().map(|(a, n)| format!("{n} {a}")).collect();
            let phase = (region_phases.as_ref())
                .map_or(String::new(), |p| format!(" at phase {:.2}", p[region]));
            println!(
                "  region {region}{phase}: {steps} steps ({}); {}",
                count.join(", "),
                strongest(correlation.region_values(region))
            );
        }
    }
    Ok(with_joint_correlation(bytes, Some(&correlation))?)
}
