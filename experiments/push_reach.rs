//! Where a model's frames-only pushes go wrong: the joint RMSE of its prediction by steps
//! from the push's end (the step the demonstration's grasp point, at table height, is
//! furthest along the push), and how far short of the demonstration's reach the performed
//! grasp point stopped on the pushes it missed.
//!
//! ```sh
//! cargo run --release --example push_reach -- assets/models/attn-sim.dmbn data/imitate [K]
//! ```
use dmbn::data::{Dataset, Sequence};
use dmbn::imitate::{imitate, Task};
use dmbn::predict::Predictor;
use dmbn::sim::Action;

/// Steps per bin, and the bins' span around the push's end.
pub const BIN: i64 = 5;
pub const FROM: i64 = -40;
pub const TO: i64 = 20;

/// Per step, how far the grasp point is along the demonstration's push (metres, from its
/// start), or `None` while it is above table height (where it pushes nothing).
fn reach(demo: &Sequence, episode: &Sequence) -> Vec<Option<f32>> {
    let object = demo
        .object
        .as_ref()
        .expect("the demonstration's object track");
    let (start, end) = (object[0], object[demo.len() - 1]);
    let push = [end[0] - start[0], end[1] - start[1]];
    let length = push[0].hypot(push[1]);
    let demo_endpoint = demo
        .endpoint
        .as_ref()
        .expect("the demonstration's endpoint");
    let low = demo_endpoint.iter().map(|e| e[2]).fold(f32::MAX, f32::min) + 0.02;
    episode
        .endpoint
        .as_ref()
        .expect("the episode's endpoint")
        .iter()
        .map(|e| {
            (e[2] < low)
                .then(|| ((e[0] - start[0]) * push[0] + (e[1] - start[1]) * push[1]) / length)
        })
        .collect()
}

fn furthest(reach: &[Option<f32>]) -> (usize, f32) {
    reach
        .iter()
        .enumerate()
        .filter_map(|(k, r)| r.map(|r| (k, r)))
        .fold((0, f32::MIN), |a, b| if b.1 > a.1 { b } else { a })
}

/// What [`push_reach`] finds on a dataset's pushes.
#[derive(Debug, Clone, PartialEq)]
pub struct Reach {
    /// Per bin of [`BIN`] steps from the push's end ([`FROM`] to [`TO`]): the predicted
    /// joints' RMSE (radians, arm joints), NaN where no step fell in it.
    pub rmse: Vec<f64>,
    /// Pushes performed.
    pub pushes: usize,
    /// The missed ones: id, how far short of the demonstration's reach the performed grasp
    /// point stopped (metres), the push's end (phase).
    pub missed: Vec<(u32, f32, f32)>,
}

impl Reach {
    /// The report `main` prints.
    pub fn table(&self) -> String {
        let mut out =
            String::from("| steps from the push's end | joint RMSE (rad) |\n|---|---:|\n");
        for (b, rmse) in self.rmse.iter().enumerate() {
            let from = FROM + b as i64 * BIN;
            out += &format!("| {from:+} to {:+} | {rmse:.3} |\n", from + BIN - 1);
        }
        out += &format!(
            "\n{} of {} pushes missed: id, how far short of the demonstration's reach the grasp \
             point stopped (cm), the push's end (phase)\n",
            self.missed.len(),
            self.pushes
        );
        for (id, short, phase) in &self.missed {
            out += &format!("{id}: {:.1} cm, {phase:.2}\n", short * 100.0);
        }
        out
    }
}

/// `predictor` imitates every push of `dataset` from `k` evenly spaced frames (blend 1, as
/// `dmbn imitate --task frames`).
pub fn push_reach(predictor: &Predictor, dataset: &Dataset, k: usize) -> Result<Reach, String> {
    let bins = ((TO - FROM) / BIN) as usize;
    let (mut se, mut values) = (vec![0.0f64; bins], vec![0usize; bins]);
    let (mut pushes, mut missed) = (0, Vec::new());
    let size = predictor.model().image_size() as u32;
    for r in dataset
        .sequences()
        .iter()
        .filter(|r| r.action == Action::Move.name())
    {
        let demo = dataset.read(r, Some(size)).map_err(|e| e.to_string())?;
        let done = imitate(predictor, &demo, Action::Move, Task::Frames, k, 1.0)
            .map_err(|e| e.to_string())?;
        let Some(done) = done else {
            continue;
        };
        pushes += 1;
        let (end, demo_reach) = furthest(&reach(&demo, &demo));
        for (t, (p, d)) in done.trajectory.iter().zip(&demo.joints).enumerate() {
            let b = t as i64 - end as i64 - FROM;
            if (0..TO - FROM).contains(&b) {
                se[(b / BIN) as usize] +=
                    (0..6).map(|j| ((p[j] - d[j]) as f64).powi(2)).sum::<f64>();
                values[(b / BIN) as usize] += 6;
            }
        }
        if !done.outcome.success {
            let performed = furthest(&reach(&demo, &done.performance)).1;
            let phase = end as f32 / (demo.len() - 1) as f32;
            missed.push((r.id, demo_reach - performed, phase));
        }
    }
    let rmse = se
        .iter()
        .zip(&values)
        .map(|(&se, &n)| {
            if n == 0 {
                f64::NAN
            } else {
                (se / n as f64).sqrt()
            }
        })
        .collect();
    Ok(Reach {
        rmse,
        pushes,
        missed,
    })
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: push_reach MODEL DATA [K]";
    let (Some(model), Some(data)) = (args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let k: usize = args
        .get(3)
        .map_or(Ok(5), |s| s.parse())
        .map_err(|_| usage)?;
    let predictor = Predictor::load(model).map_err(|e| e.to_string())?;
    let dataset = Dataset::open(data).map_err(|e| e.to_string())?;
    print!("{}", push_reach(&predictor, &dataset, k)?.table());
    Ok(())
}
