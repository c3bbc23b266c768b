//! `cargo bench --bench sim`: simulated + rendered frames per second at 64 and 128, with
//! physics and rendering timed separately. Prints the median of several repetitions over a
//! fixed set of episodes (grasp and move, seeds 0..4), single-threaded.
use std::hint::black_box;
use std::time::Instant;

use dmbn::sim::{Action, Simulator};

const REPEATS: usize = 7;
const SEEDS: u64 = 4;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Frames per second over all episodes; `render` and `physics` choose what each step does.
fn frames_per_second(size: u32, physics: bool, render: bool) -> f64 {
    let runs = (0..REPEATS)
        .map(|_| {
            let mut frames = 0usize;
            let mut elapsed = 0.0;
            for action in Action::ALL {
                for seed in 0..SEEDS {
                    let mut sim = Simulator::new(action, seed, size).expect("valid settings");
                    let mut buf = vec![0u8; (size * size * 3) as usize];
                    let start = Instant::now();
                    loop {
                        if render {
                            sim.render_into(&mut buf);
                            black_box(&buf);
                        }
                        frames += 1;
                        if !physics {
                            if frames % sim.len() == 0 {
                                break;
                            }
                            continue;
                        }
                        black_box(sim.joints());
                        if !sim.step() {
                            break;
                        }
                    }
                    elapsed += start.elapsed().as_secs_f64();
                }
            }
            frames as f64 / elapsed
        })
        .collect();
    median(runs)
}

fn main() {
    // `cargo test --benches` runs this too: keep that cheap.
    if std::env::args().any(|a| a == "--test" || a == "--list") {
        return;
    }
    println!(
        "simulator benchmark: median of {REPEATS} runs, grasp+move seeds 0..{SEEDS}, one thread"
    );
    println!(
        "{:>6} {:>18} {:>14} {:>14}",
        "size", "sim+render fps", "physics fps", "render fps"
    );
    let mut json = Vec::new();
    for size in [64u32, 128] {
        let both = frames_per_second(size, true, true);
        let physics = frames_per_second(size, true, false);
        let render = frames_per_second(size, false, true);
        println!("{size:>6} {both:>18.0} {physics:>14.0} {render:>14.0}");
        json.push(format!(
            "{{\"size\":{size},\"sim_render_fps\":{both:.0},\"physics_fps\":{physics:.0},\"render_fps\":{render:.0}}}"
        ));
    }
    println!("json: [{}]", json.join(","));
}
