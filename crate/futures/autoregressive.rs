use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

use super::{representatives, FutureScores, JointDraws, Method, Order, Sampling};
use crate::data::{Joints, Sequence};
use crate::model::{values, EncodedContexts, ModelError};
use crate::predict::{Encoding, Observations, Predictor, SequencePrediction};

/// One sampled future: what the decoders condition on once its steps are drawn, and the draws.
#[derive(Debug, Clone)]
pub struct Future {
    /// The observations plus the drawn steps, encoded: decode it for the future's mean at any
    /// target ([`Predictor::decode`], or [`Predictor::decode_joints`] for the joints alone).
    pub encoding: Encoding,
    /// The drawn steps in the order drawn: phase and joint values (dataset units).
    pub drawn: Vec<(f32, Vec<f32>)>,
}

/// S futures of the sequence `observations` show, over `target_times` (the steps to imagine,
/// increasing), with blend `blend`, drawn autoregressively (the module's doc): per future, the
/// joints at `sampling.grid` of the targets, one after another, each from the Gaussian the
/// model predicts there given the observations and the steps drawn before it, then added to
/// the contexts with the mean frame predicted there. Deterministic in `sampling.seed`; future
/// `s` is the same whatever S.
pub fn draw_futures(
    predictor: &Predictor,
    observations: &Observations,
    target_times: &[f32],
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Future>, ModelError> {
    let observed = predictor.encode_contexts(observations)?;
    draw_futures_from(predictor, &observed, target_times, blend, sampling)
}

/// [`draw_futures`] from observations already encoded (`Predictor::encode_contexts`; the
/// page's workers keep each observation's).
pub fn draw_futures_from(
    predictor: &Predictor,
    observed: &EncodedContexts,
    target_times: &[f32],
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Future>, ModelError> {
    sampling.validate()?;
    if target_times.is_empty() {
        return Err(ModelError::observation(
            "target_times",
            "is empty: expected the steps to imagine",
        ));
    }
    let has_latent = predictor.model().latent_size().is_some();
    match sampling.method {
        Method::Latent if !has_latent => {
            return Err(ModelError::observation(
                "method",
                "is latent, but this model has no latent path: expected ar or auto (train one with --latent L)",
            ))
        }
        Method::Latent | Method::Auto if has_latent => {
            return draw_latent_futures(predictor, observed, blend, sampling)
        }
        _ => {}
    }
    let correlation = match (sampling.joints, predictor.joint_correlation()) {
        (JointDraws::Correlated, None) => {
            return Err(ModelError::observation(
                "joints",
                "is correlated, but this model file holds no joint correlation: expected auto or independent (fit one with dmbn calibrate)",
            ))
        }
        (JointDraws::Independent, _) => None,
        (_, correlation) => correlation,
    };
    let grid = grid(target_times, sampling.grid);
    let end = grid.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let components = sampling.components.unwrap_or(usize::MAX);
    let times = sampling.bootstrap.then(|| observed.observed_times());
    let mut first = Vec::new();
    let candidates = (0..sampling.samples * sampling.oversample)
        .map(|s| {
            let mut rng = future_rng(sampling, s);
            let resample =
                (times.as_ref()).and_then(|times| bootstrap(times, observed.len(), &mut rng));
            let mut order = grid.clone();
            if sampling.order == Order::Random {
                for i in (1..order.len()).rev() {
                    order.swap(i, rng.random_range(0..=i));
                }
            }
            // The first step's prediction is shared only by futures that see the same
            // observations.
            let seen = seen_contexts(observed, resample.as_deref())?;
            let mut own_first = Vec::new();
            let first = match resample {
                Some(_) => &mut own_first,
                None => &mut first,
            };
            let (contexts, steps) =
                condition_on_steps(predictor, &seen, &order, blend, first, |k, mean, sigma| {
                    let eps: Vec<f32> = mean.iter().map(|_| standard_normal(&mut rng)).collect();
                    let eps = match correlation {
                        Some(r) => {
                            let pose = predictor.normalization().normalize(mean);
                            r.correlate(&pose, order[k], &eps, components)
                        }
                        None => eps,
                    };
                    // The future's end (the last target) drawn at its own τ.
                    let tau = match order[k] == end {
                        true => sampling.end_temperature,
                        false => sampling.temperature,
                    };
                    let draw = mean.iter().zip(sigma).zip(eps);
                    (draw.map(|((m, s), e)| m + tau * s * e)).collect()
                })?;
            // A candidate's contexts are rebuilt from its steps if it is kept: K × S of them
            // would hold K × S copies of every observed frame.
            let contexts = (sampling.oversample == 1).then_some(contexts);
            Ok(Candidate {
                contexts,
                resample,
                steps,
            })
        })
        .collect::<Result<Vec<_>, ModelError>>()?;
    // Where more were drawn than asked for, the representatives of their drawn steps (in
    // time order, each joint in the units the model normalises it by).
    let features: Vec<Vec<f32>> = (candidates.iter())
        .map(|candidate| {
            let mut steps: Vec<&Observations> = candidate.steps.iter().collect();
            steps.sort_by(|a, b| a.times[0].total_cmp(&b.times[0]));
            let rows = steps.into_iter();
            (rows.flat_map(|step| predictor.normalization().normalize(&step.joints))).collect()
        })
        .collect();
    let keep = representatives(&features, sampling.samples);
    let mut candidates: Vec<_> = candidates.into_iter().map(Some).collect();
    keep.into_iter()
        .map(|i| {
            let candidate = candidates[i].take().expect("each candidate kept once");
            let contexts = match candidate.contexts {
                Some(contexts) => contexts,
                None => {
                    let seen = seen_contexts(observed, candidate.resample.as_deref())?;
                    with_steps(predictor, seen, &candidate.steps)?
                }
            };
            Ok(Future {
                encoding: predictor.represent_future(&contexts, blend, sampling.stage)?,
                drawn: (candidate.steps.into_iter())
                    .map(|step| (step.times[0], step.joints))
                    .collect(),
            })
        })
        .collect()
}

/// A future drawn, before the representatives are chosen.
struct Candidate {
    /// What the decoders condition on (kept only when every drawn future is kept).
    contexts: Option<EncodedContexts>,
    /// The observations it conditions on, by index, where it sees a bootstrap resample.
    resample: Option<Vec<usize>>,
    /// Its drawn steps, in the order drawn.
    steps: Vec<Observations>,
}

/// The observed contexts a future conditions on: all of them, or its bootstrap `resample`.
fn seen_contexts(
    observed: &EncodedContexts,
    resample: Option<&[usize]>,
) -> Result<EncodedContexts, ModelError> {
    match resample {
        Some(indices) => observed.select(indices),
        None => Ok(observed.clone()),
    }
}

/// A bootstrap resample of the observations at `times`: as many indices, drawn with
/// replacement, the last of them the latest observation (where the arm is now: a future that
/// forgot it would restart from an older pose). Drawn in time order, so that the same
/// observations encoded in another order (the page's workers) give the same resample.
/// `None` with fewer than 2 observations, or where `n` contexts are not the observations at
/// `times` (a padded batch).
fn bootstrap(times: &[f32], n: usize, rng: &mut Pcg64) -> Option<Vec<usize>> {
    if n < 2 || times.len() != n {
        return None;
    }
    let mut by_time: Vec<usize> = (0..n).collect();
    by_time.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let mut indices: Vec<usize> = (0..n).map(|_| by_time[rng.random_range(0..n)]).collect();
    indices[n - 1] = by_time[n - 1];
    Some(indices)
}

/// The observations plus `steps` taken one after another: at each, `joints_at(k, μ, σ)` gives
/// the joints from the Gaussian predicted there given the contexts before it (a draw, or the
/// truth when fitting), added to the contexts with the mean frame predicted there. The
/// contexts and the steps taken (each an observation: time, mean frame, joints). The first
/// step's prediction, given the observations alone, is the same for every future: `first`
/// keeps it per time, decoded once.
fn condition_on_steps(
    predictor: &Predictor,
    observed: &EncodedContexts,
    steps: &[f32],
    blend: f32,
    first: &mut Vec<(f32, SequencePrediction)>,
    mut joints_at: impl FnMut(usize, &[f32], &[f32]) -> Vec<f32>,
) -> Result<(EncodedContexts, Vec<Observations>), ModelError> {
    let image_size = predictor.model().image_size();
    let mut contexts = observed.clone();
    let mut taken = Vec::with_capacity(steps.len());
    for (k, &t) in steps.iter().enumerate() {
        let known = (k == 0)
            .then(|| first.iter().find(|(u, _)| *u == t))
            .flatten();
        let here = match known {
            Some((_, here)) => here.clone(),
            None => predictor.decode(&predictor.represent(&contexts, blend)?, &[t])?,
        };
        if k == 0 && known.is_none() {
            first.push((t, here.clone()));
        }
        let step = Observations {
            image_size,
            frames: here.mean_frame(0),
            joints: joints_at(k, here.joint_mean_at(0), here.joint_sigma_at(0)),
            times: vec![t],
        };
        contexts = with_steps(predictor, contexts, std::slice::from_ref(&step))?;
        taken.push(step);
    }
    Ok((contexts, taken))
}

/// `contexts` with `steps` added one after another, each encoded on its own.
fn with_steps(
    predictor: &Predictor,
    mut contexts: EncodedContexts,
    steps: &[Observations],
) -> Result<EncodedContexts, ModelError> {
    for step in steps {
        contexts = contexts.cat(&predictor.encode_contexts(step)?)?;
    }
    Ok(contexts)
}

/// One drawn step's row for [`drawn_step_errors`].
#[derive(Debug, Clone, PartialEq)]
pub struct DrawnStepError {
    /// The standardised error, (truth − μ) / σ, of each joint value.
    pub error: Vec<f32>,
    /// The mean it is an error from, normalised: where the correlation's regions lie.
    pub pose: Vec<f32>,
    /// The drawn step: its index on the grid (0 first) and its phase.
    pub step: usize,
    pub phase: f32,
}

/// The standardised errors, (truth − μ) / σ, of `seq`'s joints at the grid of its `imagined`
/// steps (increasing) that autoregressive sampling with `grid` steps, left to right, would
/// draw from its `observed` steps, each step conditioned on the truth at the ones before it
/// (the conditionals a draw takes): what [`crate::model::JointCorrelation::fit`] fits on
/// (`dmbn calibrate`), each with the mean it is an error from, normalised (where the
/// correlation's regions lie). One row per grid step.
pub fn drawn_step_errors(
    predictor: &Predictor,
    seq: &Sequence,
    observed: &[usize],
    imagined: &[usize],
    blend: f32,
    grid_size: usize,
) -> Result<Vec<DrawnStepError>, ModelError> {
    let observed = predictor.encode_contexts(&Observations::from_sequence(seq, observed)?)?;
    let times = seq.times();
    let at: Vec<f32> = imagined.iter().map(|&k| times[k]).collect();
    let steps = grid(&at, grid_size);
    let truth: Vec<&[f32]> = (imagined.iter())
        .filter(|&&k| steps.contains(&times[k]))
        .map(|&k| &seq.joints[k])
        .collect();
    let mut errors = Vec::with_capacity(steps.len());
    condition_on_steps(
        predictor,
        &observed,
        &steps,
        blend,
        &mut Vec::new(),
        |k, mean, sigma| {
            let error = (truth[k].iter().zip(mean).zip(sigma)).map(|((y, m), s)| (y - m) / s);
            errors.push(DrawnStepError {
                error: error.collect(),
                pose: predictor.normalization().normalize(mean),
                step: k,
                phase: steps[k],
            });
            truth[k].to_vec()
        },
    )?;
    Ok(errors)
}

/// Future `s`'s generator: the same whatever S.
fn future_rng(sampling: &Sampling, s: usize) -> Pcg64 {
    Pcg64::seed_from_u64(
        sampling
            .seed
            .wrapping_add((s as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)),
    )
}

/// S futures through the model's latent path: per future, z drawn from the prior the
/// observations give, N(μ, (τσ)²), then the mean at every step given the observations and z.
/// Nothing is drawn step by step ([`Future::drawn`] is empty).
fn draw_latent_futures(
    predictor: &Predictor,
    observed: &EncodedContexts,
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Future>, ModelError> {
    let base = predictor.represent(observed, blend)?;
    let Some(prior) = predictor.model().prior(&base.representation) else {
        return Err(ModelError::observation(
            "method",
            "the model has no latent path",
        ));
    };
    let (mean, sigma) = (values(prior.mean), values(prior.sigma));
    (0..sampling.samples)
        .map(|s| {
            let mut rng = future_rng(sampling, s);
            let z: Vec<f32> = (mean.iter().zip(&sigma))
                .map(|(m, sd)| m + sampling.temperature * sd * standard_normal(&mut rng))
                .collect();
            Ok(Future {
                encoding: predictor.with_latent(&base, &z)?,
                drawn: Vec::new(),
            })
        })
        .collect()
}

/// The joint rows at `times` (a sequence's every step, say) of S futures drawn over `future`
/// (the times of the steps to imagine) by [`draw_futures`]: one performable trajectory each.
pub fn sample_trajectories(
    predictor: &Predictor,
    observations: &Observations,
    future: &[f32],
    times: &[f32],
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Joints>, ModelError> {
    let futures = draw_futures(predictor, observations, future, blend, sampling)?;
    trajectories(predictor, &futures, times)
}

/// The joint rows at `times` of each of `futures`: its mean given the observations and its
/// draws.
pub fn trajectories(
    predictor: &Predictor,
    futures: &[Future],
    times: &[f32],
) -> Result<Vec<Joints>, ModelError> {
    let rows = futures.iter();
    rows.map(|f| predictor.decode_joints(&f.encoding, times))
        .collect()
}

/// S futures of the encoded observations `observed`, drawn over the targets that are not an
/// observed time (`Model.sample` in wasm). Fails when every target is observed: nothing is
/// left to imagine.
pub fn draw_unobserved(
    predictor: &Predictor,
    observed: &EncodedContexts,
    target_times: &[f32],
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Future>, ModelError> {
    let times = observed.observed_times();
    let future: Vec<f32> = (target_times.iter())
        .filter(|t| !times.contains(t))
        .copied()
        .collect();
    if future.is_empty() {
        return Err(ModelError::observation(
            "target_times",
            "holds only observed times: expected steps to imagine",
        ));
    }
    draw_futures_from(predictor, observed, &future, blend, sampling)
}

/// The joint rows at `target_times` of [`draw_unobserved`]'s futures.
pub fn sample_unobserved(
    predictor: &Predictor,
    observed: &EncodedContexts,
    target_times: &[f32],
    blend: f32,
    sampling: &Sampling,
) -> Result<Vec<Joints>, ModelError> {
    let futures = draw_unobserved(predictor, observed, target_times, blend, sampling)?;
    trajectories(predictor, &futures, target_times)
}

/// Each future's mean frame at time `t` (RGB bytes): where it ends, for `t` its last step.
pub fn frames_at(
    predictor: &Predictor,
    futures: &[Future],
    t: f32,
) -> Result<Vec<Vec<u8>>, ModelError> {
    let frames = futures.iter();
    frames
        .map(|f| Ok(predictor.decode(&f.encoding, &[t])?.mean_frame(0)))
        .collect()
}

/// S futures of `seq` from its `observed` steps scored against it at the `imagined` ones
/// (increasing), beside the single mean's prediction ([`FutureScores`]). The futures are
/// scored as drawn, never as representatives ([`Sampling::as_drawn`]): the energy score
/// is proper for draws from the predictive distribution, and representatives spread wider
/// than draws would flatter it.
pub fn score_futures(
    predictor: &Predictor,
    seq: &Sequence,
    observed: &[usize],
    imagined: &[usize],
    blend: f32,
    sampling: &Sampling,
) -> Result<FutureScores, ModelError> {
    // The observations encoded once: for the futures and for the single mean.
    let observed = predictor.encode_contexts(&Observations::from_sequence(seq, observed)?)?;
    let times = seq.times();
    let at: Vec<f32> = imagined.iter().map(|&k| times[k]).collect();
    let futures = draw_futures_from(predictor, &observed, &at, blend, &sampling.as_drawn())?;
    let futures = trajectories(predictor, &futures, &at)?;
    let mean = predictor.decode_joints(&predictor.represent(&observed, blend)?, &at)?;
    let truth = Joints::from_slices(seq.joints.width(), imagined.iter().map(|&k| &seq.joints[k]));
    let all: Vec<usize> = (0..imagined.len()).collect();
    Ok(FutureScores::of(&futures, &mean, &truth, &all))
}

/// `g` of `targets`, evenly spaced by index and ending at the last (all of them when there are
/// no more than `g`).
fn grid(targets: &[f32], g: usize) -> Vec<f32> {
    let m = targets.len();
    if m <= g {
        return targets.to_vec();
    }
    (1..=g)
        .map(|i| targets[(i * (m - 1) + g / 2) / g])
        .collect()
}

/// A standard normal draw (Box-Muller through libm: the same bits natively and in wasm).
fn standard_normal(rng: &mut Pcg64) -> f32 {
    let u1 = 1.0 - rng.random_range(0.0f64..1.0);
    let u2 = rng.random_range(0.0f64..1.0);
    (libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(core::f64::consts::TAU * u2)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_is_evenly_spaced_and_ends_at_the_last_target() {
        let targets: Vec<f32> = (0..41).map(|k| k as f32 / 40.0).collect();
        assert_eq!(grid(&targets, 4), vec![0.25, 0.5, 0.75, 1.0]);
        assert_eq!(grid(&targets[..3], 4), targets[..3].to_vec());
        assert_eq!(grid(&targets, 1), vec![1.0]);
    }

    #[test]
    fn a_bootstrap_resample_keeps_the_latest_observation_last() {
        let mut rng = Pcg64::seed_from_u64(3);
        let times = [0.3, 0.0, 0.15];
        let mut seen = [false; 3];
        for _ in 0..50 {
            let indices = bootstrap(&times, 3, &mut rng).unwrap();
            assert_eq!((indices.len(), indices[2]), (3, 0), "{indices:?}");
            for &i in &indices[..2] {
                seen[i] = true;
            }
        }
        assert_eq!(seen, [true; 3], "some observation never drawn");
        // The same observations in another order: the same observations drawn.
        let (mut a, mut b) = (Pcg64::seed_from_u64(9), Pcg64::seed_from_u64(9));
        let sorted = bootstrap(&[0.0, 0.15, 0.3], 3, &mut a).unwrap();
        let shuffled = bootstrap(&times, 3, &mut b).unwrap();
        let at = |t: &[f32], i: &[usize]| i.iter().map(|&k| t[k]).collect::<Vec<f32>>();
        assert_eq!(at(&[0.0, 0.15, 0.3], &sorted), at(&times, &shuffled));
        assert_eq!(bootstrap(&[0.5], 1, &mut rng), None);
        assert_eq!(bootstrap(&times, 4, &mut rng), None);
    }

    #[test]
    fn normal_draws_have_mean_0_and_variance_1() {
        let mut rng = Pcg64::seed_from_u64(7);
        let n = 20_000;
        let draws: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng) as f64).collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((var - 1.0).abs() < 0.04, "{var}");
    }
}
