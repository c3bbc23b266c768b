//! The best a model that performs *mean* joints could do from K evenly spaced glimpses of a
//! scripted push, when the timing is all it cannot see.
//!
//! For each push demonstration (the simulator's seeds SEED..SEED+N, as `dmbn simulate --seed
//! SEED` makes them) the script's free parameters (where the object is, the push's direction
//! and distance) are given, its segments' durations are not: every combination of durations
//! the script could draw is weighted by how well it puts the grasp point where the
//! demonstration had it at the K observed phases (a Gaussian of SIGMA metres), and the
//! weighted mean of their joint trajectories, at the demonstration's phases, is performed
//! with the object in place: the posterior mean that a network trained with squared error
//! approximates, given perfect reading of where the gripper is. The timing is then the only
//! uncertainty: if the mean over the timings left open cut the push's corner, this would miss.
//!
//! ```sh
//! cargo run --release --example push_oracle -- 300000 100 0.01 [K]
//! ```
use dmbn::data::Sequence;
use dmbn::quality::Scenario;
use dmbn::sim::{episode, perform, Action, Outcome, PushMiss, Simulator, Trajectory};

/// Combinations weighted below this (relative to the likeliest) are left out.
pub const NEGLIGIBLE: f64 = 1e-4;

/// One demonstration's posterior-mean push.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OraclePush {
    pub seed: u64,
    /// Timings that weigh (above [`NEGLIGIBLE`]), of every one the script could draw.
    pub weighing: usize,
    pub timings: usize,
    /// Whether the performed push landed the object (as `dmbn imitate` judges it), and how
    /// it missed otherwise.
    pub landed: bool,
    pub miss: Option<PushMiss>,
    /// Where the object ended, from the demonstration's spot (cm).
    pub object_error_cm: f32,
    /// Squared error of the arm joints summed over the steps, and how many values.
    pub se: f64,
    pub values: usize,
}

/// The posterior-mean push of the demonstration of simulator seed `seed` from `k` glimpses
/// of its grasp point (a Gaussian of `sigma` metres), performed with the object in place.
pub fn oracle_push(seed: u64, sigma: f64, k: usize) -> Result<OraclePush, String> {
    let demo = episode(Action::Move, seed, 64).map_err(|e| e.to_string())?;
    let object = Simulator::placement(seed);
    let (script, truth) = Simulator::script(Action::Move, object, seed);
    let len = demo.len();
    let phases = demo.times();
    // The phases of the steps `dmbn imitate --task frames` observes.
    let observed: Vec<f32> = Scenario::Interp
        .steps(len, k)
        .ok_or("a demonstration longer than K steps")?
        .observed
        .iter()
        .map(|&s| Sequence::phase(s, len))
        .collect();
    let total = |d: &[usize]| d.iter().sum::<usize>() as f32;
    let grasp_point = |d: &[usize], phase: f32| script.at(d, phase * total(d)).0.position;
    let seen: Vec<_> = observed.iter().map(|&p| grasp_point(&truth, p)).collect();
    // Every timing the script could draw, with its log-likelihood.
    let mut timings = vec![(Vec::new(), 0.0f64)];
    for segment in &script.segments {
        timings = timings
            .into_iter()
            .flat_map(|(d, _)| {
                segment
                    .steps
                    .clone()
                    .map(move |s| ([d.clone(), vec![s]].concat(), 0.0))
            })
            .collect();
    }
    for (d, ll) in timings.iter_mut() {
        *ll = -observed
            .iter()
            .zip(&seen)
            .map(|(&p, s)| (grasp_point(d, p) - *s).length_squared() as f64)
            .sum::<f64>()
            / (2.0 * sigma * sigma);
    }
    let best = timings.iter().map(|t| t.1).fold(f64::MIN, f64::max);
    let weighted: Vec<_> = timings
        .iter()
        .map(|(d, ll)| (d, (ll - best).exp()))
        .filter(|(_, w)| *w > NEGLIGIBLE)
        .collect();
    let z: f64 = weighted.iter().map(|(_, w)| w).sum();
    let mut mean = vec![[0.0f64; 6]; len];
    for (d, w) in &weighted {
        let joints = script.plan(d).joints;
        for (m, &phase) in mean.iter_mut().zip(&phases) {
            let s = phase * (joints.len() - 1) as f32;
            let i = (s as usize).min(joints.len() - 2);
            let f = s - i as f32;
            for (j, mj) in m.iter_mut().enumerate() {
                let q = joints[i][j] * (1.0 - f) + joints[i + 1][j] * f;
                *mj += w / z * q as f64;
            }
        }
    }
    let rows: Vec<[f32; 7]> = mean
        .iter()
        .map(|m| std::array::from_fn(|j| if j < 6 { m[j] as f32 } else { 0.0 }))
        .collect();
    let (mut se, mut values) = (0.0, 0);
    for (r, t) in rows.iter().zip(&demo.joints) {
        se += (0..6).map(|j| ((r[j] - t[j]) as f64).powi(2)).sum::<f64>();
        values += 6;
    }
    let trajectory = Trajectory::new(rows).map_err(|e| e.to_string())?;
    let performed = perform(&trajectory, object, 64).map_err(|e| e.to_string())?;
    let outcome = Outcome::judge(Action::Move, &performed, &demo).ok_or("an empty performance")?;
    Ok(OraclePush {
        seed,
        weighing: weighted.len(),
        timings: timings.len(),
        landed: outcome.success,
        miss: (!outcome.success)
            .then(|| outcome.push_error_cm.map_or(PushMiss::Aside, |e| e.miss())),
        object_error_cm: outcome.object_error_cm,
        se,
        values,
    })
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: push_oracle SEED N SIGMA_M [K]";
    let arg = |i: usize| -> Result<&String, String> { args.get(i).ok_or(usage.into()) };
    let seed0: u64 = arg(1)?.parse().map_err(|_| usage)?;
    let n: u64 = arg(2)?.parse().map_err(|_| usage)?;
    let sigma: f64 = arg(3)?.parse().map_err(|_| usage)?;
    let k: usize = args
        .get(4)
        .map_or(Ok(5), |s| s.parse())
        .map_err(|_| usage)?;
    let (mut landed, mut misses, mut se, mut values) = (0, [0; 3], 0.0f64, 0usize);
    for seed in seed0..seed0 + n {
        let push = oracle_push(seed, sigma, k)?;
        match push.miss {
            None => landed += 1,
            Some(PushMiss::Short) => misses[0] += 1,
            Some(PushMiss::Long) => misses[1] += 1,
            Some(PushMiss::Aside) => misses[2] += 1,
        }
        (se, values) = (se + push.se, values + push.values);
        eprintln!(
            "seed {seed}: {} of {} timings weigh, object {:.1} cm from the spot",
            push.weighing, push.timings, push.object_error_cm
        );
    }
    println!(
        "seeds {seed0}..{}, {k} glimpses, σ {sigma} m: {landed}/{n} pushes landed, misses \
         short / long / aside {} / {} / {}, joint RMSE {:.4} rad",
        seed0 + n - 1,
        misses[0],
        misses[1],
        misses[2],
        (se / values.max(1) as f64).sqrt()
    );
    Ok(())
}
