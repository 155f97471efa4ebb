//! Plots of the report, drawn with `plotters` into inline SVG (no fonts needed: the
//! browser renders the text; no network, no files).

use crate::error::Result;
use crate::plot::{perr, svg, Frame};
use plotters::prelude::*;
use std::ops::Range;

pub(super) const W: u32 = 420;
pub(super) const H: u32 = 300;

pub(super) fn empty(title: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\"><text x=\"20\" y=\"40\" font-size=\"16\">{}: no data</text></svg>",
        super::html::escape(title)
    )
}

/// The report's frame ([`W`] x [`H`]): `title`, the axes' ranges and descriptions, six
/// labels on each axis, a y label area of `y_area` pixels.
pub(super) fn report_frame<'a>(
    title: &'a str,
    (x, y): (Range<f64>, Range<f64>),
    desc: (&'a str, &'a str),
    y_area: u32,
) -> Frame<'a> {
    Frame {
        size: (W, H),
        title,
        margin: 8,
        label_areas: (36, y_area),
        x,
        y,
        desc,
        labels: (Some(6), Some(6)),
        x_formatter: None,
        x_mesh: true,
        legend: None,
    }
}

/// Histogram of `values` in `bins` equal bins.
pub fn histogram(title: &str, x_label: &str, values: &[f64], bins: usize) -> Result<String> {
    let vals: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if vals.is_empty() || bins == 0 {
        return Ok(empty(title));
    }
    let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if hi - lo < 1e-12 {
        (lo - 0.5 * lo.abs().max(1e-3), hi + 0.5 * hi.abs().max(1e-3))
    } else {
        (lo, hi)
    };
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &vals {
        let i = (((v - lo) / width).floor().max(0.0) as usize).min(bins - 1);
        if let Some(c) = counts.get_mut(i) {
            *c += 1;
        }
    }
    let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.1;
    let frame = Frame {
        labels: (Some(6), Some(5)),
        ..report_frame(title, (lo..hi, 0.0..top), (x_label, "count"), 44)
    };
    svg(frame, |chart| {
        chart
            .draw_series(counts.iter().enumerate().map(|(i, &c)| {
                let x0 = lo + i as f64 * width;
                Rectangle::new(
                    [(x0, 0.0), (x0 + width, c as f64)],
                    RGBColor(70, 110, 200).filled(),
                )
            }))
            .map_err(perr)?;
        Ok(())
    })
}

/// Bar chart of counts per label (e.g. per ISO).
pub fn bars(title: &str, x_label: &str, labelled: &[(String, usize)]) -> Result<String> {
    if labelled.is_empty() {
        return Ok(empty(title));
    }
    let n = labelled.len();
    let top = labelled.iter().map(|x| x.1).max().unwrap_or(1).max(1) as f64 * 1.1;
    let labels: Vec<String> = labelled.iter().map(|x| x.0.clone()).collect();
    let label_of = |x: &f64| {
        let i = x.round();
        if (x - i).abs() < 1e-6 && i >= 0.0 {
            labels.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    let range = (-0.5..(n as f64 - 0.5), 0.0..top);
    let frame = Frame {
        labels: (Some(n.min(12)), None),
        x_formatter: Some(&label_of),
        x_mesh: false,
        ..report_frame(title, range, (x_label, "count"), 44)
    };
    svg(frame, |chart| {
        chart
            .draw_series(labelled.iter().enumerate().map(|(i, (_, c))| {
                let x = i as f64;
                Rectangle::new(
                    [(x - 0.35, 0.0), (x + 0.35, *c as f64)],
                    RGBColor(200, 120, 50).filled(),
                )
            }))
            .map_err(perr)?;
        Ok(())
    })
}

/// A 2-D Gaussian drawn as its 1, 2 and 3 sigma ellipses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Mean.
    pub mean: [f64; 2],
    /// Covariance.
    pub cov: [[f64; 2]; 2],
}

impl Ellipse {
    /// Points of the k-sigma contour.
    pub fn contour(&self, k: f64, n: usize) -> Vec<(f64, f64)> {
        // Cholesky of the covariance (clamped to be positive semi-definite).
        let a = self.cov[0][0].max(0.0).sqrt();
        let b = if a > 0.0 { self.cov[1][0] / a } else { 0.0 };
        let c = (self.cov[1][1] - b * b).max(0.0).sqrt();
        (0..=n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                let (u, v) = (k * t.cos(), k * t.sin());
                (self.mean[0] + a * u, self.mean[1] + b * u + c * v)
            })
            .collect()
    }
}

/// Scatter of chromaticities (`points`: (x, y, kind index)) over an optional ellipse.
/// `kinds` names the colour classes (legend).
pub fn chromaticity(
    title: &str,
    axes: (&str, &str),
    points: &[(f64, f64, usize)],
    kinds: &[&str],
    ellipse: Option<Ellipse>,
) -> Result<String> {
    const COLORS: [RGBColor; 4] = [
        RGBColor(30, 90, 200),
        RGBColor(220, 120, 0),
        RGBColor(200, 30, 60),
        RGBColor(40, 150, 60),
    ];
    let mut xs: Vec<f64> = points.iter().map(|p| p.0).collect();
    let mut ys: Vec<f64> = points.iter().map(|p| p.1).collect();
    let contour = ellipse.map(|e| e.contour(3.0, 96));
    if let Some(c) = &contour {
        xs.extend(c.iter().map(|p| p.0));
        ys.extend(c.iter().map(|p| p.1));
    }
    xs.retain(|v| v.is_finite());
    ys.retain(|v| v.is_finite());
    if xs.is_empty() || ys.is_empty() {
        return Ok(empty(title));
    }
    let range = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let pad = ((hi - lo) * 0.08).max(1e-3);
        (lo - pad)..(hi + pad)
    };
    let frame = Frame {
        // plotters' default position, written out
        legend: (!points.is_empty()).then_some(SeriesLabelPosition::MiddleRight),
        ..report_frame(title, (range(&xs), range(&ys)), axes, 48)
    };
    svg(frame, |chart| {
        if let Some(e) = ellipse {
            for (k, shade) in [(1.0, 120u8), (2.0, 170), (3.0, 210)] {
                chart
                    .draw_series(LineSeries::new(
                        e.contour(k, 96),
                        RGBColor(shade, shade, shade).stroke_width(2),
                    ))
                    .map_err(perr)?;
            }
            chart
                .draw_series(std::iter::once(Cross::new(
                    (e.mean[0], e.mean[1]),
                    5,
                    BLACK.stroke_width(2),
                )))
                .map_err(perr)?;
        }
        for (ki, name) in kinds.iter().enumerate() {
            let color = COLORS[ki % COLORS.len()];
            let pts: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.2 == ki && p.0.is_finite() && p.1.is_finite())
                .map(|p| (p.0, p.1))
                .collect();
            if pts.is_empty() {
                continue;
            }
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, color.filled())))
                .map_err(perr)?
                .label(*name)
                .legend(move |(x, y)| Circle::new((x + 6, y), 4, color.filled()));
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_are_svg() {
        let h = histogram("dim", "factor", &[0.1, 0.2, 0.2, 0.5], 8).unwrap();
        assert!(
            h.starts_with("<svg") && h.contains("<rect") && h.contains("dim"),
            "{h}"
        );
        assert!(histogram("x", "y", &[], 4).unwrap().contains("no data"));
        assert!(histogram("one", "v", &[2.0], 4).unwrap().contains("<rect"));
        let b = bars("iso", "ISO", &[("1600".into(), 3), ("3200".into(), 3)]).unwrap();
        assert!(b.contains("1600") && b.contains("3200"));
        let e = Ellipse {
            mean: [0.5, 0.6],
            cov: [[0.01, 0.002], [0.002, 0.02]],
        };
        let c = e.contour(1.0, 4);
        assert!(
            (c[0].0 - 0.6).abs() < 1e-12 && (c[0].1 - 0.62).abs() < 1e-12,
            "{c:?}"
        );
        let s = chromaticity(
            "ill",
            ("r/g", "b/g"),
            &[(0.5, 0.6, 0), (0.55, 0.5, 1)],
            &["ambient", "light"],
            Some(e),
        )
        .unwrap();
        assert!(
            s.contains("<circle") && s.contains("<polyline") && s.contains("ambient"),
            "{s}"
        );
    }
}
