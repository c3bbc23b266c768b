use image::RgbImage;
use plotters::prelude::*;

use super::joint_plot::{rendered, Canvas};
use super::FigureError;
use crate::quality::{CoverageSummary, QualityReport, LEVELS};

/// Line colours of the models, in the order of the reports' rows.
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 90, 180),
    RGBColor(214, 96, 20),
    RGBColor(40, 150, 60),
    RGBColor(170, 40, 160),
    RGBColor(200, 40, 40),
    RGBColor(90, 90, 90),
];

/// Which coverage of a calibration a panel shows.
type Pick = fn(&crate::quality::Calibration) -> Option<CoverageSummary>;

/// The calibration curves of `dmbn score --plot`: per scenario (a row of panels) and for the
/// joints and the moving pixels (the columns), the fraction of true values inside each
/// central interval of the predicted Gaussian against the fraction it claims, one line per
/// model; the diagonal is a calibrated model, below it an over-confident one.
pub fn calibration_plot(
    reports: &[QualityReport],
    width: u32,
    height: u32,
) -> Result<RgbImage, FigureError> {
    if reports.is_empty() {
        return Err(FigureError::Input {
            what: "reports",
            reason: "none: score at least one scenario".into(),
        });
    }
    rendered(width, height, |root| draw(reports, root))
}

fn draw(reports: &[QualityReport], root: &Canvas) -> Result<(), Box<dyn std::error::Error>> {
    let panels = root.split_evenly((reports.len(), 2));
    let kinds: [(&str, Pick); 2] = [
        ("joints", |c| c.joints),
        ("moving pixels", |c| c.moving_pixels),
    ];
    for (r, report) in reports.iter().enumerate() {
        for (k, (what, summary)) in kinds.iter().enumerate() {
            let caption = format!("{}: {what}", report.scenario);
            let mut chart = ChartBuilder::on(&panels[r * 2 + k])
                .caption(caption, ("sans-serif", 15))
                .margin(8)
                .x_label_area_size(34)
                .y_label_area_size(46)
                .build_cartesian_2d(0f64..1f64, 0f64..1f64)?;
            chart
                .configure_mesh()
                .x_desc("nominal coverage")
                .y_desc("observed")
                .x_labels(6)
                .y_labels(6)
                .label_style(("sans-serif", 11))
                .light_line_style(WHITE)
                .draw()?;
            chart.draw_series(LineSeries::new(
                [(0.0, 0.0), (1.0, 1.0)],
                BLACK.mix(0.4).stroke_width(1),
            ))?;
            let models = report.rows.iter().filter(|row| row.model);
            for (i, row) in models.enumerate() {
                let Some(curve) = row.quality.calibration.and_then(|c| summary(&c)) else {
                    continue;
                };
                let colour = COLOURS[i % COLOURS.len()];
                let points: Vec<(f64, f64)> = LEVELS.iter().copied().zip(curve.curve).collect();
                chart
                    .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
                    .label(row.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2))
                    });
                chart.draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 3, colour.filled())),
                )?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .label_font(("sans-serif", 11))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .draw()?;
        }
    }
    Ok(())
}
