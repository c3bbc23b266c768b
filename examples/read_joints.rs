//! The joints a model's network reads from K evenly spaced frames alone (blend 1; its mirror
//! stage, if any, left out): its joint means at the observed steps, K rows per sequence written as its joint file in the DMBN layout
//! (`OUT/<id>/<action>/joint_<id>.txt`), for `python/experiments/mirror_interpolation.py
//! --read-train/--read-test` to interpolate.
//!
//! ```sh
//! cargo run --release --example read_joints -- assets/models/attn-sim.dmbn data/imitate 0-99 runs/read
//! ```
use dmbn::data::Dataset;
use dmbn::predict::{Observations, Predictor};
use dmbn::quality::Scenario;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: read_joints MODEL DATA A-B OUT [K]";
    let [_, model, data, ids, out, ..] = &args[..] else {
        return Err(usage.into());
    };
    let k: usize = args
        .get(5)
        .map_or(Ok(5), |s| s.parse())
        .map_err(|_| usage)?;
    let (a, b) = ids.split_once('-').ok_or(usage)?;
    let ids = a.parse::<u32>().map_err(|_| usage)?..=b.parse::<u32>().map_err(|_| usage)?;
    let predictor = Predictor::load(model).map_err(|e| e.to_string())?;
    let size = predictor.model().image_size() as u32;
    let dataset = Dataset::open(data).map_err(|e| e.to_string())?;
    for r in dataset.sequences().iter().filter(|r| ids.contains(&r.id)) {
        let seq = dataset.read(r, Some(size)).map_err(|e| e.to_string())?;
        let steps = Scenario::Interp
            .steps(seq.len(), k)
            .ok_or("a sequence too short")?
            .observed;
        let observed = Observations::from_sequence(&seq, &steps).map_err(|e| e.to_string())?;
        let read = predictor.reads(&observed).map_err(|e| e.to_string())?;
        let text: String = read
            .rows()
            .map(|row| {
                let values: Vec<String> = row.iter().map(|v| v.to_string()).collect();
                values.join(" ") + "\n"
            })
            .collect();
        let dir = format!("{out}/{}/{}", r.id, r.action);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{dir}: {e}"))?;
        let path = format!("{dir}/joint_{}.txt", r.id);
        std::fs::write(&path, text).map_err(|e| format!("{path}: {e}"))?;
    }
    Ok(())
}
