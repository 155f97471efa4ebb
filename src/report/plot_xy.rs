//! The report's CIE 1931 xy plot of a sample's lights: each light's colour (its camera
//! neutral mapped to xy through the camera's own colour matrices) against the Planckian
//! locus with iso-CCT ticks, so that a light off the locus (a green or magenta cast no real
//! lamp has) shows at a glance.

use super::plot::{empty, report_frame};
use crate::color::planck::{planck_uv, uv_to_xy, CCT_RANGE};
use crate::error::Result;
use crate::plot::{perr, svg, Frame};
use plotters::prelude::*;

/// Temperatures of the iso-CCT ticks, kelvin.
pub const TICKS: [f64; 9] = [
    1500.0, 2000.0, 2500.0, 3000.0, 3500.0, 4000.0, 5000.0, 6500.0, 10000.0,
];
/// Half length of a tick along its isotemperature line, in Duv.
pub const TICK_DUV: f64 = 0.005;
/// Duv of the two guide curves beside the locus (real lamps lie within them).
pub const GUIDE_DUV: f64 = 0.01;

/// The xy of CCT `t` kelvin and distance `duv` from the locus (perpendicular to it in CIE
/// 1960 uv, positive towards green).
pub fn at_duv(t: f64, duv: f64) -> (f64, f64) {
    let p = planck_uv(t);
    let q = planck_uv(1e6 / (1e6 / t + 1.0));
    let (du, dv) = (q[0] - p[0], q[1] - p[1]);
    let n = (du * du + dv * dv).sqrt().max(1e-300);
    // unit normal pointing up (v increasing)
    let (nu, nv) = if du > 0.0 {
        (-dv / n, du / n)
    } else {
        (dv / n, -du / n)
    };
    let xy = uv_to_xy([p[0] + duv * nu, p[1] + duv * nv]);
    (xy[0], xy[1])
}

/// The iso-CCT tick at `t` kelvin: the xy ends of the segment from Duv -[`TICK_DUV`] to
/// +[`TICK_DUV`] across the locus.
pub fn tick(t: f64) -> [(f64, f64); 2] {
    [at_duv(t, -TICK_DUV), at_duv(t, TICK_DUV)]
}

/// Scatter of lights in CIE xy (`points`: (x, y, kind index), `kinds` the legend) over the
/// Planckian locus and iso-CCT ticks.
pub fn planckian(title: &str, points: &[(f64, f64, usize)], kinds: &[&str]) -> Result<String> {
    const COLORS: [RGBColor; 4] = [
        RGBColor(30, 90, 200),
        RGBColor(220, 120, 0),
        RGBColor(200, 30, 60),
        RGBColor(40, 150, 60),
    ];
    let pts: Vec<&(f64, f64, usize)> = points
        .iter()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return Ok(empty(title));
    }
    // The lights' range, at least 0.12 x 0.08 around them (a few hundred kelvin of locus).
    let range = |v: &[f64], min_span: f64| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let pad = ((hi - lo) * 0.15)
            .max((min_span - (hi - lo)) / 2.0)
            .max(0.005);
        (lo - pad)..(hi + pad)
    };
    let xr = range(&pts.iter().map(|p| p.0).collect::<Vec<_>>(), 0.12);
    let yr = range(&pts.iter().map(|p| p.1).collect::<Vec<_>>(), 0.08);
    let inside = |p: &(f64, f64)| xr.contains(&p.0) && yr.contains(&p.1);
    let curve = |duv: f64| -> Vec<(f64, f64)> {
        (0..=400)
            .map(|i| {
                let (lo, hi) = (1e6 / CCT_RANGE.1, 1e6 / CCT_RANGE.0);
                at_duv(1e6 / (lo + (hi - lo) * i as f64 / 400.0), duv)
            })
            .collect()
    };
    let frame = Frame {
        legend: Some(SeriesLabelPosition::LowerRight),
        ..report_frame(title, (xr.clone(), yr.clone()), ("CIE x", "CIE y"), 48)
    };
    svg(frame, |chart| {
        // The locus and the guides, piecewise: only the parts inside the window.
        let guide = RGBColor(170, 170, 170);
        for (duv, color, label) in [
            (0.0, BLACK, "Planckian locus"),
            (GUIDE_DUV, guide, "Duv +-0.01"),
            (-GUIDE_DUV, guide, ""),
        ] {
            let mut run: Vec<(f64, f64)> = Vec::new();
            let mut runs = Vec::new();
            for p in curve(duv) {
                if inside(&p) {
                    run.push(p);
                } else if !run.is_empty() {
                    runs.push(std::mem::take(&mut run));
                }
            }
            runs.push(run);
            for (i, r) in runs.into_iter().filter(|r| r.len() > 1).enumerate() {
                let s = chart
                    .draw_series(LineSeries::new(r, color.stroke_width(1)))
                    .map_err(perr)?;
                if i == 0 && !label.is_empty() {
                    s.label(label)
                        .legend(move |(x, y)| PathElement::new([(x, y), (x + 12, y)], color));
                }
            }
        }
        for t in TICKS {
            let [a, b] = tick(t);
            if !(inside(&a) && inside(&b)) {
                continue;
            }
            let grey = RGBColor(120, 120, 120);
            chart
                .draw_series(LineSeries::new([a, b], grey.stroke_width(1)))
                .map_err(perr)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{t:.0} K"),
                    b,
                    ("sans-serif", 11).into_font().color(&grey),
                )))
                .map_err(perr)?;
        }
        for (ki, name) in kinds.iter().enumerate() {
            let color = COLORS[ki % COLORS.len()];
            let mine: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| p.2 == ki)
                .map(|p| (p.0, p.1))
                .collect();
            if mine.is_empty() {
                continue;
            }
            chart
                .draw_series(mine.into_iter().map(|p| Circle::new(p, 4, color.filled())))
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
    use crate::color::planck::{cct_duv, planck_xy};

    #[test]
    fn ticks_cross_the_locus_at_their_temperature() {
        for t in TICKS {
            let [a, b] = tick(t);
            let (ta, da) = cct_duv([a.0, a.1]).unwrap();
            let (tb, db) = cct_duv([b.0, b.1]).unwrap();
            assert!(
                (da + TICK_DUV).abs() < 1e-4 && (db - TICK_DUV).abs() < 1e-4,
                "{t}: {da} {db}"
            );
            // an isotemperature line: both ends have (nearly) the tick's CCT
            assert!(
                (ta / t - 1.0).abs() < 0.01 && (tb / t - 1.0).abs() < 0.01,
                "{t}: {ta} {tb}"
            );
        }
    }

    #[test]
    fn plot_has_locus_ticks_and_lights() {
        let a = planck_xy(2500.0);
        let svg = planckian(
            "Lights in CIE xy",
            &[(a[0], a[1], 0), (a[0] + 0.01, a[1], 1), (f64::NAN, 0.4, 2)],
            &["ambient", "local", "bulb"],
        )
        .unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("Planckian locus"),
            "{svg}"
        );
        assert!(svg.contains("2500 K") && svg.contains("CIE x"), "{svg}");
        assert!(svg.contains("<circle"), "{svg}");
        assert!(!svg.contains("bulb"), "no bulb drawn: {svg}");
        assert!(planckian("x", &[], &["a"]).unwrap().contains("no data"));
    }
}
