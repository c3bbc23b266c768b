//! Figures for the command line (native only): the joint plot of a prediction (true curves,
//! predicted mean, ±2σ band, observed points), the evaluation figure, the quality benchmark's
//! calibration curves and PNG output. Text is drawn with an embedded
//! DejaVu Sans Mono, so plots look the same on every machine.
mod calibration_plot;
mod error;
mod eval_figure;
mod joint_plot;
mod png;

pub use calibration_plot::calibration_plot;
pub use error::FigureError;
pub use eval_figure::eval_figure;
pub use joint_plot::{joint_plot, JointPlot};
pub use png::{encode_png, save_png};
