use std::sync::Once;

use image::RgbImage;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use super::FigureError;
use crate::data::Joints;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");
static REGISTER: Once = Once::new();

/// Makes the embedded font the "sans-serif" of every figure (once).
pub(crate) fn register() {
    REGISTER.call_once(|| {
        // The font is compiled in and known to parse; a failure would only lose the text.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// What a joint plot shows: one panel per joint value over the phase `times` (D = the
/// number of `names`).
#[derive(Debug, Clone, Copy)]
pub struct JointPlot<'a> {
    /// `T` phases of the predicted (and true) steps.
    pub times: &'a [f32],
    /// `T × D` true joint values, if known.
    pub truth: Option<&'a Joints>,
    /// `T × D` predicted mean.
    pub mean: &'a [f32],
    /// `T × D` predicted σ (the band is mean ± 2σ).
    pub sigma: &'a [f32],
    /// Observed steps: (phase, D joint values).
    pub observed: &'a [(f32, Vec<f32>)],
    /// Sampled futures (`dmbn sample`), each `T × D`: drawn as thin lines, a fan.
    pub samples: &'a [Vec<f32>],
    /// Panel titles, one per joint value (a model's `ModelConfig::joint_labels`).
    pub names: &'a [String],
}

/// Draws `plot` as a `width × height` RGB image: a 4 × 2 grid of panels, each with the true
/// curve (black), the predicted mean (blue) inside its ±2σ band (light blue), the sampled
/// futures (thin orange lines) and the observed points (red).
pub fn joint_plot(plot: &JointPlot, width: u32, height: u32) -> Result<RgbImage, FigureError> {
    let (t, d) = (plot.times.len(), plot.names.len());
    let samples = plot.samples.iter().map(|s| ("samples", s.len()));
    for (what, len) in [("mean", plot.mean.len()), ("sigma", plot.sigma.len())]
        .into_iter()
        .chain(samples)
    {
        if d == 0 || len != t * d {
            return Err(FigureError::Input {
                what,
                reason: format!("holds {len} values, expected {t} steps × {d} (one per name)"),
            });
        }
    }
    if let Some(truth) = plot.truth {
        if truth.len() != t || truth.width() != d {
            return Err(FigureError::Input {
                what: "truth",
                reason: format!(
                    "holds {} steps of {}, expected {t} of {d}",
                    truth.len(),
                    truth.width()
                ),
            });
        }
    }
    if let Some((_, row)) = plot.observed.iter().find(|(_, r)| r.len() != d) {
        return Err(FigureError::Input {
            what: "observed",
            reason: format!("a step of {} values, expected {d}", row.len()),
        });
    }
    rendered(width, height, |root| draw(plot, root))
}

/// Where a figure is drawn: its whole white bitmap.
pub(crate) type Canvas<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// A `width × height` RGB image that `draw` paints with plotters on a white canvas (the font
/// registered).
pub(crate) fn rendered(
    width: u32,
    height: u32,
    draw: impl FnOnce(&Canvas) -> Result<(), Box<dyn std::error::Error>>,
) -> Result<RgbImage, FigureError> {
    register();
    let mut buffer = vec![255u8; width as usize * height as usize * 3];
    let painted = || -> Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    };
    painted().map_err(|e| FigureError::Draw(e.to_string()))?;
    RgbImage::from_raw(width, height, buffer)
        .ok_or_else(|| FigureError::Draw("plot buffer of the wrong size".into()))
}

fn draw(plot: &JointPlot, root: &Canvas) -> Result<(), Box<dyn std::error::Error>> {
    let band = RGBColor(160, 190, 235);
    let mean_colour = RGBColor(31, 90, 180);
    let sample_colour = RGBColor(240, 140, 40);
    let x_end = plot.times.iter().copied().fold(1.0f32, f32::max);
    let d = plot.names.len();
    // Two panels a row, and one cell for the legend.
    let grid = ((d + 1).div_ceil(2), 2);
    for (j, area) in root.split_evenly(grid).iter().enumerate().take(d) {
        let value = |row: &[f32]| row[j];
        let rows = |v: &'_ [f32]| -> Vec<f32> { v.chunks_exact(d).map(value).collect() };
        let (mean, sigma) = (rows(plot.mean), rows(plot.sigma));
        let truth: Vec<f32> = plot
            .truth
            .map_or_else(Vec::new, |rows| rows.rows().map(|r| r[j]).collect());
        let observed: Vec<(f32, f32)> = plot.observed.iter().map(|(t, r)| (*t, r[j])).collect();
        let samples: Vec<Vec<f32>> = plot.samples.iter().map(|s| rows(s)).collect();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        let values = mean
            .iter()
            .zip(&sigma)
            .flat_map(|(m, s)| [m - 2.0 * s, m + 2.0 * s])
            .chain(truth.iter().copied())
            .chain(samples.iter().flatten().copied())
            .chain(observed.iter().map(|o| o.1));
        for v in values.filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            let c = if lo.is_finite() { lo } else { 0.0 };
            (lo, hi) = (c - 0.5, c + 0.5);
        }
        let pad = 0.05 * (hi - lo);
        let mut chart = ChartBuilder::on(area)
            .caption(&plot.names[j], ("sans-serif", 14))
            .margin(6)
            .x_label_area_size(22)
            .y_label_area_size(46)
            .build_cartesian_2d(0f32..x_end, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_labels(5)
            .y_labels(4)
            .label_style(("sans-serif", 11))
            .light_line_style(WHITE)
            .draw()?;
        let mut outline: Vec<(f32, f32)> = plot
            .times
            .iter()
            .zip(mean.iter().zip(&sigma))
            .map(|(&t, (m, s))| (t, m + 2.0 * s))
            .collect();
        outline.extend(
            plot.times
                .iter()
                .zip(mean.iter().zip(&sigma))
                .rev()
                .map(|(&t, (m, s))| (t, m - 2.0 * s)),
        );
        chart.draw_series(std::iter::once(Polygon::new(outline, band.filled())))?;
        for sample in &samples {
            chart.draw_series(LineSeries::new(
                plot.times.iter().copied().zip(sample.iter().copied()),
                sample_colour.stroke_width(1),
            ))?;
        }
        if !truth.is_empty() {
            chart.draw_series(LineSeries::new(
                plot.times.iter().copied().zip(truth.iter().copied()),
                BLACK.stroke_width(1),
            ))?;
        }
        chart.draw_series(LineSeries::new(
            plot.times.iter().copied().zip(mean.iter().copied()),
            mean_colour.stroke_width(2),
        ))?;
        chart.draw_series(observed.iter().map(|&p| Circle::new(p, 4, RED.filled())))?;
    }
    let samples_drawn = !plot.samples.is_empty();
    if let Some(legend) = root.split_evenly(grid).get(d) {
        let style = ("sans-serif", 13).into_font();
        let lines = [
            ("true", BLACK),
            ("predicted mean", mean_colour),
            ("mean ± 2σ", band),
            ("sampled futures", sample_colour),
            ("observed", RED),
        ];
        let shown = |(label, _): &&(&str, RGBColor)| *label != "sampled futures" || samples_drawn;
        for (i, (label, colour)) in lines.iter().filter(shown).enumerate() {
            let y = 30 + 24 * i as i32;
            legend.draw(&Rectangle::new([(30, y - 6), (60, y + 6)], colour.filled()))?;
            legend.draw(&Text::new(*label, (70, y - 7), style.clone()))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_and_rejects_bad_lengths() {
        let times = [0.0, 0.5, 1.0];
        let mean = [0.1f32; 21];
        let sigma = [0.05f32; 21];
        let truth = Joints::from_rows(&[[0.2f32; 7]; 3]);
        let names = crate::model::ModelConfig::new(crate::model::ModelKind::Pte).joint_labels();
        let observed = [(0.5, vec![0.2; 7])];
        let plot = JointPlot {
            times: &times,
            truth: Some(&truth),
            mean: &mean,
            sigma: &sigma,
            observed: &observed,
            samples: &[],
            names: &names,
        };
        let image = joint_plot(&plot, 400, 300).unwrap();
        assert_eq!(image.dimensions(), (400, 300));
        assert!(
            image.pixels().any(|p| p.0 == [255, 0, 0]),
            "observed points are drawn"
        );
        let bad = JointPlot {
            mean: &mean[..20],
            ..plot
        };
        assert!(joint_plot(&bad, 400, 300).is_err());
        // Sampled futures: a fan of thin orange lines; one of the wrong length is refused.
        let futures = [vec![0.3f32; 21], vec![-0.1f32; 21]];
        let fan = JointPlot {
            samples: &futures,
            ..plot
        };
        let orange = |image: &RgbImage| image.pixels().any(|p| p.0 == [240, 140, 40]);
        assert!(orange(&joint_plot(&fan, 400, 300).unwrap()));
        assert!(!orange(&joint_plot(&plot, 400, 300).unwrap()));
        let short = [vec![0.3f32; 20]];
        let bad = JointPlot {
            samples: &short,
            ..plot
        };
        assert!(joint_plot(&bad, 400, 300).is_err());
        // Any number of joint values: three panels and the legend.
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let three = JointPlot {
            times: &times,
            truth: None,
            mean: &mean[..9],
            sigma: &sigma[..9],
            observed: &[],
            samples: &[],
            names: &names,
        };
        assert_eq!(
            joint_plot(&three, 400, 300).unwrap().dimensions(),
            (400, 300)
        );
        assert!(joint_plot(
            &JointPlot {
                mean: &mean,
                ..three
            },
            400,
            300
        )
        .is_err());
    }
}
