//! The arm performs joint trajectories made elsewhere (joint files in the DMBN layout,
//! `FOLDER/<id>/<action>/joint_<id>.txt`, one row per step of the demonstration: e.g. by
//! `python/experiments/mirror_interpolation.py`), each with the object where the
//! demonstration had it, judged as `dmbn imitate` judges a model's.
//!
//! ```sh
//! cargo run --release --example perform_trajectories -- data/imitate runs/mlp-0.03
//! ```
use std::path::Path;

use dmbn::data::{read_joints, Dataset, Disk, JOINTS};
use dmbn::imitate::enact;
use dmbn::sim::{Action, PushMiss};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: perform_trajectories DATA FOLDER";
    let (Some(data), Some(folder)) = (args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let dataset = Dataset::open(data).map_err(|e| e.to_string())?;
    println!(
        "| action | performed | succeeded | push misses short / long / aside | joint RMSE (rad) |"
    );
    println!("|---|---:|---:|---:|---:|");
    for action in [Action::Grasp, Action::Move] {
        let (mut n, mut ok, mut misses, mut se, mut values) = (0, 0, [0; 3], 0.0, 0);
        for r in dataset
            .sequences()
            .iter()
            .filter(|r| r.action == action.name())
        {
            let demo = dataset.read(r, None).map_err(|e| e.to_string())?;
            let dir = Path::new(folder).join(r.id.to_string()).join(action.name());
            let rows = read_joints(&Disk, &dir, r.id).map_err(|e| e.to_string())?;
            let rows = rows
                .rows()
                .map(<[f32; JOINTS]>::try_from)
                .collect::<Result<Vec<_>, _>>()
                .map_err(|_| {
                    format!(
                        "{}: {} joint values a step, the arm takes {JOINTS}",
                        dir.display(),
                        rows.width()
                    )
                })?;
            let done = enact(&demo, action, rows, Vec::new())
                .map_err(|e| format!("{}: {e}", dir.display()))?;
            n += 1;
            se += done.joint_se.iter().sum::<f64>();
            values += done.joint_steps * done.joint_se.len();
            match done.outcome.push_error_cm.map(|e| e.miss()) {
                _ if done.outcome.success => ok += 1,
                Some(PushMiss::Short) => misses[0] += 1,
                Some(PushMiss::Long) => misses[1] += 1,
                Some(PushMiss::Aside) => misses[2] += 1,
                None => {}
            }
        }
        let rmse = (se / values.max(1) as f64).sqrt();
        let [s, l, a] = misses;
        println!("| {action} | {n} | {ok} | {s} / {l} / {a} | {rmse:.3} |");
    }
    Ok(())
}
