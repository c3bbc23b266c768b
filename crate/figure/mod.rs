//! Figures for the command line (native only): the joint plot of a prediction (true curves,
//! predicted mean, ±2σ band, observed points), the evaluation figure and PNG output. Text is drawn with an embedded
//! DejaVu Sans Mono, so plots look the same on every machine.
mod error;
mod eval_figure;
mod joint_plot;
mod png;

pub use error::FigureError;
pub use eval_figure::eval_figure;
pub use joint_plot::{joint_plot, JointPlot};
pub use png::{encode_png, save_png};
