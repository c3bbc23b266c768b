use image::{imageops, RgbImage};
use plotters::prelude::*;

use super::joint_plot::register;
use super::{joint_plot, FigureError, JointPlot};
use crate::data::Joints;
use crate::eval::{evenly_spaced, Evaluation};

/// Width of the row-label column, pixels.
const LABEL: u32 = 120;
/// Space for a caption above each frame row, pixels.
const CAPTION: u32 = 16;

/// A figure like the paper's Figures 2-3 for one evaluation: observed frames (y_o), generated
/// mean frames (ỹ_t) with their σ heat maps, and the targets (y_t) at `columns` evenly spaced
/// steps, frames scaled up `zoom` times; a joint curve per value named in `names` (target,
/// mean ± 2σ, observed points) below.
pub fn eval_figure(
    e: &Evaluation,
    names: &[String],
    columns: usize,
    zoom: u32,
) -> Result<RgbImage, FigureError> {
    register();
    let seq = &e.shown.sequence;
    let s = seq.image_size;
    let cell = s * zoom;
    let shown_obs: Vec<usize> = evenly_spaced(e.observed.len(), columns)
        .into_iter()
        .map(|i| e.observed[i])
        .collect();
    let targets = evenly_spaced(seq.len(), columns);
    let width = LABEL + columns as u32 * (cell + 4);
    let row_h = cell + CAPTION;
    let grid_h = 4 * row_h + 8;
    let frame = |bytes: Vec<u8>| -> Result<RgbImage, FigureError> {
        let img = RgbImage::from_raw(s, s, bytes)
            .ok_or_else(|| FigureError::Draw("frame of the wrong size".into()))?;
        Ok(imageops::resize(
            &img,
            cell,
            cell,
            imageops::FilterType::Nearest,
        ))
    };
    let scale = e.prediction.max_image_sigma();
    let rows: [(&str, Vec<(usize, RgbImage)>); 4] = [
        (
            "observed y_o",
            shown_obs
                .iter()
                .map(|&k| Ok((k, frame(seq.frame(k).to_vec())?)))
                .collect::<Result<_, FigureError>>()?,
        ),
        (
            "generated ỹ_t",
            targets
                .iter()
                .map(|&k| Ok((k, frame(e.prediction.mean_frame(k))?)))
                .collect::<Result<_, FigureError>>()?,
        ),
        (
            "σ (heat map)",
            targets
                .iter()
                .map(|&k| Ok((k, frame(e.prediction.sigma_map(k, scale))?)))
                .collect::<Result<_, FigureError>>()?,
        ),
        (
            "target y_t",
            targets
                .iter()
                .map(|&k| Ok((k, frame(seq.frame(k).to_vec())?)))
                .collect::<Result<_, FigureError>>()?,
        ),
    ];

    let mut grid = vec![255u8; (width * grid_h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut grid, (width, grid_h)).into_drawing_area();
        let font = ("sans-serif", 13).into_font();
        for (r, (label, frames)) in rows.iter().enumerate() {
            let y = (r as u32 * row_h) as i32;
            root.draw(&Text::new(
                *label,
                (6, y + CAPTION as i32 + cell as i32 / 2 - 7),
                font.clone(),
            ))
            .map_err(|e| FigureError::Draw(e.to_string()))?;
            for (c, (k, _)) in frames.iter().enumerate() {
                let x = (LABEL + c as u32 * (cell + 4)) as i32;
                let caption = format!("t={:.2}", e.shown.times[*k]);
                root.draw(&Text::new(
                    caption,
                    (x, y + 1),
                    ("sans-serif", 11).into_font(),
                ))
                .map_err(|e| FigureError::Draw(e.to_string()))?;
            }
        }
        root.present()
            .map_err(|e| FigureError::Draw(e.to_string()))?;
    }
    let mut grid = RgbImage::from_raw(width, grid_h, grid)
        .ok_or_else(|| FigureError::Draw("figure buffer of the wrong size".into()))?;
    for (r, (_, frames)) in rows.iter().enumerate() {
        for (c, (_, img)) in frames.iter().enumerate() {
            let x = LABEL + c as u32 * (cell + 4);
            let y = r as u32 * row_h + CAPTION;
            imageops::replace(&mut grid, img, x as i64, y as i64);
        }
    }

    // Joint curves over the time stamps, sorted (a p-sequence's stamps are shuffled).
    let mut order: Vec<usize> = (0..seq.len()).collect();
    order.sort_by(|&a, &b| e.shown.times[a].total_cmp(&e.shown.times[b]));
    let times: Vec<f32> = order.iter().map(|&k| e.shown.times[k]).collect();
    let d = seq.joints.width();
    let truth = Joints::from_slices(d, order.iter().map(|&k| &seq.joints[k]));
    let gather = |v: &[f32]| -> Vec<f32> {
        order
            .iter()
            .flat_map(|&k| v[k * d..(k + 1) * d].to_vec())
            .collect()
    };
    let (mean, sigma) = (
        gather(&e.prediction.joint_mean),
        gather(&e.prediction.joint_sigma),
    );
    let observed: Vec<(f32, Vec<f32>)> = e
        .observed
        .iter()
        .map(|&k| (e.shown.times[k], seq.joints[k].to_vec()))
        .collect();
    let plot = JointPlot {
        times: &times,
        truth: Some(&truth),
        mean: &mean,
        sigma: &sigma,
        observed: &observed,
        samples: &[],
        names,
    };
    let joints = joint_plot(&plot, width, (width * 2 / 3).max(500))?;
    let mut out =
        RgbImage::from_pixel(width, grid_h + joints.height(), image::Rgb([255, 255, 255]));
    imageops::replace(&mut out, &grid, 0, 0);
    imageops::replace(&mut out, &joints, 0, grid_h as i64);
    Ok(out)
}
