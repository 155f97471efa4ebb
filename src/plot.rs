//! The plots' common frame (the report's and `calibrate noise --physics`'s), drawn with
//! `plotters` into an SVG string (no fonts needed: the browser renders the text). Needs the
//! `cli` feature.

use crate::error::{Error, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::ops::Range;

/// A plotting error as a day2night error ("plot: ...").
pub(crate) fn perr<E: std::fmt::Display>(e: E) -> Error {
    Error::invalid(format!("plot: {e}"))
}

/// The frame of one plot: its size, caption, axes and mesh labels (what every plot of the
/// report and of `calibrate noise --physics` sets up the same way).
pub(crate) struct Frame<'a> {
    /// Width and height, pixels.
    pub size: (u32, u32),
    /// The caption.
    pub title: &'a str,
    /// Margin around the chart, pixels.
    pub margin: u32,
    /// Sizes of the x and y label areas, pixels.
    pub label_areas: (u32, u32),
    /// The x axis' range.
    pub x: Range<f64>,
    /// The y axis' range.
    pub y: Range<f64>,
    /// The x and y axes' descriptions.
    pub desc: (&'a str, &'a str),
    /// How many labels on the x and y axes (`None`: plotters' default).
    pub labels: (Option<usize>, Option<usize>),
    /// The x labels' text (`None`: the numbers).
    pub x_formatter: Option<&'a dyn Fn(&f64) -> String>,
    /// Draw the vertical mesh lines.
    pub x_mesh: bool,
    /// Where the legend of the labelled series goes (`None`: no legend).
    pub legend: Option<SeriesLabelPosition>,
}

/// A chart on an SVG string with `f64` axes, as [`svg`] hands it to its caller.
pub(crate) type Chart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// One SVG plot: a white background, `frame`'s caption, axes and mesh, what `draw` puts on
/// the chart, then the legend of the series `draw` labelled.
pub(crate) fn svg(
    frame: Frame<'_>,
    draw: impl FnOnce(&mut Chart<'_, '_>) -> Result<()>,
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, frame.size).into_drawing_area();
        root.fill(&WHITE).map_err(perr)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(frame.title, ("sans-serif", 16))
            .margin(frame.margin)
            .x_label_area_size(frame.label_areas.0)
            .y_label_area_size(frame.label_areas.1)
            .build_cartesian_2d(frame.x, frame.y)
            .map_err(perr)?;
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(frame.desc.0).y_desc(frame.desc.1);
        if let Some(n) = frame.labels.0 {
            mesh.x_labels(n);
        }
        if let Some(n) = frame.labels.1 {
            mesh.y_labels(n);
        }
        if let Some(f) = frame.x_formatter {
            mesh.x_label_formatter(f);
        }
        if !frame.x_mesh {
            mesh.disable_x_mesh();
        }
        mesh.draw().map_err(perr)?;
        draw(&mut chart)?;
        if let Some(position) = frame.legend {
            chart
                .configure_series_labels()
                .position(position)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(perr)?;
        }
        root.present().map_err(perr)?;
    }
    Ok(svg)
}
