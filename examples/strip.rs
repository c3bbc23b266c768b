//! Renders a strip of frames from a grasp and a move episode into `docs/episodes.png`
//! (the picture in the README): `cargo run --release --example strip [-- OUT.png SEED SIZE]`.
use dmbn::sim::{episode, Action};
use image::{imageops, RgbImage};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .get(1)
        .map(String::as_str)
        .unwrap_or("docs/episodes.png");
    let seed: u64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1);
    let size: u32 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(128);
    let columns = 8;
    let mut strip = RgbImage::new(size * columns, size * 2);
    for (row, action) in Action::ALL.into_iter().enumerate() {
        let seq = episode(action, seed, size)?;
        for c in 0..columns {
            let k = (c as usize * (seq.len() - 1)) / (columns as usize - 1);
            let frame =
                RgbImage::from_raw(size, size, seq.frame(k).to_vec()).ok_or("frame size")?;
            imageops::replace(
                &mut strip,
                &frame,
                (c * size) as i64,
                (row as u32 * size) as i64,
            );
        }
        println!("{action}: {} steps, digest {}", seq.len(), seq.digest());
    }
    strip.save(out)?;
    println!("wrote {out}");
    Ok(())
}
