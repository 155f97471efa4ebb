//! `day2night report OUT_DIR`: a self-contained HTML page to judge a dataset at a glance.
pub mod build;
pub mod html;
pub mod plot;
pub mod plot_xy;
pub mod thumb;

pub use build::{build, Illuminants, LightMark, ReportOptions, ReportSummary, Visuals};
pub mod real;
