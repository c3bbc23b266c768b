//! The joints a model reads from frames alone (blend 1) at random glimpse layouts: per
//! sequence DRAWS layouts of 2-8 glimpses, evenly spaced (first and last included) or one at a
//! random step of each of n equal stretches, alternately; one JSON line per layout (`id`,
//! `action`, `steps`, `reads`: the joint means at those steps), for
//! `python/experiments/mirror_stage.py` to learn from.
//!
//! ```sh
//! cargo run --release --example read_layouts -- assets/models/attn-sim.dmbn data/sim2000 0-1799 runs/layouts.jsonl 6
//! ```
use dmbn::data::{write_atomic, Dataset, Sequence};
use dmbn::predict::{Observations, Predictor};
use rand::{RngExt, SeedableRng};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: read_layouts MODEL DATA A-B OUT.jsonl DRAWS";
    let [_, model, data, ids, out, draws] = &args[..] else {
        return Err(usage.into());
    };
    let draws: usize = draws.parse().map_err(|_| usage)?;
    let (a, b) = ids.split_once('-').ok_or(usage)?;
    let ids = a.parse::<u32>().map_err(|_| usage)?..=b.parse::<u32>().map_err(|_| usage)?;
    let predictor = Predictor::load(model).map_err(|e| e.to_string())?;
    let size = predictor.model().image_size() as u32;
    let dataset = Dataset::open(data).map_err(|e| e.to_string())?;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let mut lines = String::new();
    for r in dataset.sequences().iter().filter(|r| ids.contains(&r.id)) {
        let seq = dataset.read(r, Some(size)).map_err(|e| e.to_string())?;
        let t = seq.len();
        for d in 0..draws {
            let k = rng.random_range(2..=8usize).min(t);
            let steps: Vec<usize> = if d % 2 == 0 {
                (0..k)
                    .map(|i| (i as f32 * (t - 1) as f32 / (k - 1) as f32).round() as usize)
                    .collect()
            } else {
                (0..k)
                    .map(|i| rng.random_range(i * t / k..(i + 1) * t / k))
                    .collect()
            };
            let observed = Observations::from_sequence(&seq, &steps).map_err(|e| e.to_string())?;
            let times: Vec<f32> = steps.iter().map(|&s| Sequence::phase(s, t)).collect();
            let reads = predictor
                .predict_joints(&observed, &times, 1.0)
                .map_err(|e| e.to_string())?;
            let line = serde_json::json!({
                "id": r.id, "action": r.action.to_string(), "steps": steps, "reads": reads,
            });
            lines += &format!("{line}\n");
        }
    }
    write_atomic(out.as_ref(), lines.as_bytes()).map_err(|e| e.to_string())
}
