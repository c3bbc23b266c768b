//! The simulator as a library: renders a strip of frames from a grasp and a move episode (one
//! row each, `COLUMNS` frames evenly spaced over the action) into a PNG, by default
//! `docs/episodes.png`.
//!
//! ```sh
//! cargo run --release --example strip [-- OUT.png SEED SIZE]
//! ```
use dmbn::sim::{episode, Action};
use image::{imageops, RgbImage};

/// Frames a row.
const COLUMNS: u32 = 8;

/// The strip of seed `seed`'s episodes at `size`×`size` pixels a frame: a row per action,
/// [`COLUMNS`] frames evenly spaced from the first step to the last; and per action a line
/// saying how long its episode is, with its digest.
pub fn strip(seed: u64, size: u32) -> Result<(RgbImage, Vec<String>), Box<dyn std::error::Error>> {
    let mut strip = RgbImage::new(size * COLUMNS, size * 2);
    let mut lines = Vec::new();
    for (row, action) in Action::ALL.into_iter().enumerate() {
        let seq = episode(action, seed, size)?;
        for c in 0..COLUMNS {
            let k = (c as usize * (seq.len() - 1)) / (COLUMNS as usize - 1);
            let frame =
                RgbImage::from_raw(size, size, seq.frame(k).to_vec()).ok_or("frame size")?;
            imageops::replace(
                &mut strip,
                &frame,
                (c * size) as i64,
                (row as u32 * size) as i64,
            );
        }
        lines.push(format!(
            "{action}: {} steps, digest {}",
            seq.len(),
            seq.digest()
        ));
    }
    Ok((strip, lines))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .get(1)
        .map(String::as_str)
        .unwrap_or("docs/episodes.png");
    let seed: u64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let size: u32 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(128);
    let (strip, lines) = strip(seed, size)?;
    for line in lines {
        println!("{line}");
    }
    strip.save(out)?;
    println!("wrote {out}");
    Ok(())
}
