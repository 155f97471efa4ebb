//! Calibration of the physics-based noise model ([`crate::noise::physics`]) from dark frames
//! (no light, lens cap on) and flat frames (a uniform, unsaturated field), per ISO:
//!
//! - **Row noise** (darks): per frame, the mean of `x - black(site)` of each active-area row
//!   and column parity; the variance of the row means across rows (even and odd rows
//!   separately, so a wrong per-site black level cannot pose as row noise), averaged over
//!   frames, minus the share of the per-sample noise in a row mean
//!   (`(sigma_read^2 + 1/12) / W`): `sigma_row^2`.
//! - **Read noise** (darks): the residuals `x - black - rowmean(row, parity)`; their variance
//!   (corrected for the fitted row means, minus the rounding variance 1/12 DN^2) is
//!   `sigma_read^2`; `lambda` maximizes the Tukey-lambda probability-plot correlation
//!   (PPCC) of up to [`PPCC_SAMPLES`] residuals, dithered by `U(-1/2, 1/2)` to undo the
//!   integer storage. `|lambda - 0.1349| <= ` [`GAUSSIAN_TOLERANCE`] marks the read noise
//!   Gaussian.
//! - **Gain K** (flats): flats of one ISO sorted by mean level and paired (1st+2nd, ...);
//!   per pair, `mu` = mean of `x - black` over both frames and `v = var(A - B) / 2` (the
//!   difference removes the fixed pattern: PRNU, vignetting), which is
//!   `K mu + sigma_read^2 + sigma_row^2 + 1/12`. `K` is the least-squares slope of `v`
//!   against `mu` through the dark point `(0, v0)` measured on the darks. With two or more
//!   flat levels a free line is fitted too and reported (its intercept should match `v0`).
//!
//! Refusals: fewer than [`MIN_DARK_FRAMES`] darks or [`MIN_FLAT_FRAMES`] flats at an ISO,
//! frames without an ISO, geometry/level mismatches, flats with more than
//! [`MAX_CLIPPED_FRACTION`] clipped samples or whose mean lies within 5 standard
//! deviations of white ("saturated"), flats whose 4x4 tile means spread by more than
//! [`MAX_UNEVENNESS`] of the largest ("uneven"), flat pairs whose levels differ by more
//! than [`MAX_PAIR_MISMATCH`], flats not brighter than the dark noise, and LinearizationTables.

use super::{check_same_capture, SameCapture};
use crate::error::{Error, Result};
use crate::noise::physics::{PhysicsModel, PhysicsPoint};
use crate::noise::tukey;
use crate::normalize::Normalizer;
use crate::raw::RawImage;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Fewest dark frames per ISO.
pub const MIN_DARK_FRAMES: usize = 2;
/// Fewest flat frames per ISO (one pair).
pub const MIN_FLAT_FRAMES: usize = 2;
/// Residuals used for the PPCC shape fit.
pub const PPCC_SAMPLES: usize = 200_000;
/// Order statistics evaluated per PPCC correlation.
pub const PPCC_POINTS: usize = 4000;
/// `|lambda - 0.1349|` at or below which the read noise is taken as Gaussian.
pub const GAUSSIAN_TOLERANCE: f64 = 0.01;
/// Largest fraction of clipped samples (stored 0 or >= white) in a flat.
pub const MAX_CLIPPED_FRACTION: f64 = 1e-4;
/// Largest `(max - min) / max` of a flat's 4x4 tile means.
pub const MAX_UNEVENNESS: f64 = 0.5;
/// Largest relative level difference within a flat pair.
pub const MAX_PAIR_MISMATCH: f64 = 0.05;

/// Dark-frame statistics at one ISO.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DarkFit {
    /// Frames.
    pub frames: usize,
    /// Variance of row means (mean over frames), DN^2.
    pub row_mean_var: f64,
    /// Residual variance after removing row means (dof-corrected, including rounding), DN^2.
    pub residual_var: f64,
    /// Residual excess kurtosis (dithered samples).
    pub residual_excess_kurtosis: f64,
    /// Best PPCC.
    pub ppcc: f64,
    /// Dark point `v0 = residual_var + sigma_row^2` of the mean-variance line, DN^2.
    pub v0: f64,
}

/// One flat pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlatPair {
    /// The two files.
    pub files: [String; 2],
    /// Mean signal above black, DN.
    pub mean: f64,
    /// `var(A - B) / 2`, DN^2.
    pub var: f64,
}

/// Fit details at one ISO.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IsoFit {
    /// ISO.
    pub iso: u32,
    /// Dark statistics.
    pub dark: DarkFit,
    /// Flat pairs used.
    pub flats: Vec<FlatPair>,
    /// Free line `v = slope * mu + intercept` when the flats give two or more levels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_line: Option<[f64; 2]>,
}

/// `calibrate noise --physics` output: a physics model file plus fit details.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsCalibration {
    /// The model (what synth reads).
    #[serde(flatten)]
    pub model: PhysicsModel,
    /// Per ISO fit details (ignored by synth).
    pub fits: Vec<IsoFit>,
    /// Warnings (e.g. an odd flat left out).
    #[serde(default, skip_serializing_if = "<[_]>::is_empty")]
    pub warnings: crate::diagnostics::Diagnostics,
}

/// A frame with its display name.
pub type Named<'a> = (&'a str, &'a RawImage);

fn iso_of(name: &str, img: &RawImage) -> Result<u32> {
    img.meta.exif.iso.filter(|&i| i > 0).ok_or_else(|| {
        Error::invalid(format!(
            "{name}: no Exif ISO (calibrate noise --physics --iso N gives one)"
        ))
    })
}

/// Signal above black per active-area site, row-major.
fn above_black(img: &RawImage, norm: &Normalizer) -> Vec<f64> {
    let a = img.active_area();
    let (top, left, w, h) = (a.top as usize, a.left as usize, a.width(), a.height());
    let mut out = Vec::with_capacity(w * h);
    let mut blk = vec![0.0; w];
    for r in 0..h {
        norm.black_row(r, &mut blk);
        let src = &img.data[(top + r) * img.width + left..][..w];
        out.extend(src.iter().zip(&blk).map(|(&x, &b)| x as f64 - b));
    }
    out
}

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

struct DarkOut {
    fit: DarkFit,
    sigma_read: f64,
    sigma_row: f64,
    lambda: f64,
    gaussian: bool,
}

fn fit_darks(darks: &[Named], norm: &Normalizer) -> Result<DarkOut> {
    let a = darks[0].1.active_area();
    let (w, h) = (a.width(), a.height());
    if w < 4 || h < 4 {
        return Err(Error::invalid("dark frames: active area smaller than 4x4"));
    }
    let (wc0, wc1) = (w.div_ceil(2), w / 2);
    let mut row_var_sum = 0.0;
    let (mut ss, mut dof) = (0.0, 0.0);
    let total = darks.len() * w * h;
    let stride = total.div_ceil(PPCC_SAMPLES).max(1);
    let mut picked = Vec::with_capacity(total / stride + 1);
    let mut idx = 0usize;
    let mut dither = 0x5EED_u64;
    for (_, img) in darks {
        let d = above_black(img, norm);
        let mut means = vec![0.0; h];
        for r in 0..h {
            let row = &d[r * w..][..w];
            let (mut s0, mut s1) = (0.0, 0.0);
            for (c, v) in row.iter().enumerate() {
                if c & 1 == 0 {
                    s0 += v;
                } else {
                    s1 += v;
                }
            }
            let m0 = s0 / wc0 as f64;
            let m1 = if wc1 > 0 { s1 / wc1 as f64 } else { m0 };
            means[r] = (m0 * wc0 as f64 + m1 * wc1 as f64) / w as f64;
            for (c, v) in row.iter().enumerate() {
                let e = v - if c & 1 == 0 { m0 } else { m1 };
                ss += e * e;
                if idx.is_multiple_of(stride) {
                    let u = (splitmix(&mut dither) >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                    picked.push(e + u);
                }
                idx += 1;
            }
            dof += (w - if wc1 > 0 { 2 } else { 1 }) as f64;
        }
        // variance of row means, even and odd rows separately
        let mut v = 0.0;
        for par in 0..2 {
            let m: Vec<f64> = means.iter().skip(par).step_by(2).copied().collect();
            let mu = m.iter().sum::<f64>() / m.len() as f64;
            v += m.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (m.len() - 1) as f64;
        }
        row_var_sum += v / 2.0;
    }
    let residual_var = ss / dof;
    let row_mean_var = row_var_sum / darks.len() as f64;
    let sigma_read = (residual_var - 1.0 / 12.0).max(0.0).sqrt();
    let sigma_row = (row_mean_var - residual_var / w as f64).max(0.0).sqrt();
    picked.retain(|v| v.is_finite());
    picked.sort_by(f64::total_cmp);
    let n = picked.len() as f64;
    let mu = picked.iter().sum::<f64>() / n;
    let m2 = picked.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / n;
    let m4 = picked.iter().map(|x| (x - mu).powi(4)).sum::<f64>() / n;
    let (lambda, ppcc) = if m2 > 0.0 {
        tukey::fit_lambda_ppcc(&picked, PPCC_POINTS)
    } else {
        (tukey::LAMBDA_NORMAL, f64::NAN)
    };
    Ok(DarkOut {
        fit: DarkFit {
            frames: darks.len(),
            row_mean_var,
            residual_var,
            residual_excess_kurtosis: if m2 > 0.0 { m4 / (m2 * m2) - 3.0 } else { 0.0 },
            ppcc,
            v0: residual_var + sigma_row * sigma_row,
        },
        sigma_read,
        sigma_row,
        lambda,
        gaussian: (lambda - tukey::LAMBDA_NORMAL).abs() <= GAUSSIAN_TOLERANCE,
    })
}

/// Mean above black, after checks (clipping, unevenness).
fn flat_mean(name: &str, img: &RawImage, norm: &Normalizer) -> Result<(f64, Vec<f64>)> {
    let a = img.active_area();
    let (w, h) = (a.width(), a.height());
    let d = above_black(img, norm);
    let white = norm.white;
    let clipped = img
        .data
        .chunks(img.width)
        .skip(a.top as usize)
        .take(h)
        .flat_map(|r| &r[a.left as usize..][..w])
        .filter(|&&x| x == 0 || x as f64 >= white)
        .count();
    if clipped as f64 > MAX_CLIPPED_FRACTION * (w * h) as f64 {
        return Err(Error::invalid(format!(
            "{name}: saturated flat: {clipped} of {} samples clipped (0 or >= white {white}); expose less",
            w * h
        )));
    }
    let mut tiles = [[0.0f64; 2]; 16];
    for (i, v) in d.iter().enumerate() {
        let (r, c) = (i / w, i % w);
        let t = &mut tiles[(r * 4 / h) * 4 + c * 4 / w];
        t[0] += v;
        t[1] += 1.0;
    }
    let tm: Vec<f64> = tiles
        .iter()
        .filter(|t| t[1] > 0.0)
        .map(|t| t[0] / t[1])
        .collect();
    let (lo, hi) = tm
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if hi <= 0.0 || (hi - lo) / hi > MAX_UNEVENNESS {
        return Err(Error::invalid(format!(
            "{name}: uneven flat: 4x4 tile means {lo:.1}..{hi:.1} DN above black (spread > {} of the largest); shoot a uniform field",
            MAX_UNEVENNESS
        )));
    }
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    Ok((mean, d))
}

fn fit_flats(
    iso: u32,
    flats: &[Named],
    norm: &Normalizer,
    dark: &DarkOut,
    warnings: &mut crate::diagnostics::Diagnostics,
) -> Result<(f64, Vec<FlatPair>, Option<[f64; 2]>)> {
    let mut measured = Vec::new();
    for (name, img) in flats {
        let (m, d) = flat_mean(name, img, norm)?;
        measured.push((name.to_string(), m, d));
    }
    measured.sort_by(|a, b| a.1.total_cmp(&b.1));
    if measured.len() % 2 == 1 {
        let last = measured.pop().map(|m| m.0).unwrap_or_default();
        warnings.warn(
            crate::diagnostics::Code::CalibrateOddFlats,
            format!("ISO {iso}: odd number of flats, {last} (the brightest) left out of the pairs"),
        );
    }
    let range = norm.white - norm.black_at(0, 0).max(norm.black_at(1, 1));
    let mut pairs = Vec::new();
    for ch in measured.chunks_exact(2) {
        let ((na, ma, da), (nb, mb, db)) =
            ((&ch[0].0, ch[0].1, &ch[0].2), (&ch[1].0, ch[1].1, &ch[1].2));
        let mean = (ma + mb) / 2.0;
        if (mb - ma).abs() > MAX_PAIR_MISMATCH * mean.abs().max(1e-9) {
            return Err(Error::invalid(format!(
                "ISO {iso}: flats {na} ({ma:.1} DN) and {nb} ({mb:.1} DN) differ by more than {} %: shoot flats in pairs of equal exposure",
                MAX_PAIR_MISMATCH * 100.0
            )));
        }
        let n = da.len() as f64;
        let dm = mb - ma;
        let var = da
            .iter()
            .zip(db)
            .map(|(a, b)| (b - a - dm).powi(2))
            .sum::<f64>()
            / (n - 1.0)
            / 2.0;
        if mean <= 2.0 * dark.fit.v0.sqrt().max(0.5) {
            return Err(Error::invalid(format!(
                "ISO {iso}: flats {na}, {nb}: mean {mean:.2} DN above black is within the dark noise; expose more"
            )));
        }
        if mean + 5.0 * var.sqrt() >= range {
            return Err(Error::invalid(format!(
                "ISO {iso}: saturated flats {na}, {nb}: mean {mean:.1} DN + 5 sigma reaches white; expose less"
            )));
        }
        pairs.push(FlatPair {
            files: [na.clone(), nb.clone()],
            mean,
            var,
        });
    }
    let v0 = dark.fit.v0;
    let (sxy, sxx) = pairs.iter().fold((0.0, 0.0), |(sxy, sxx), p| {
        (sxy + p.mean * (p.var - v0), sxx + p.mean * p.mean)
    });
    let k = sxy / sxx;
    let free = if pairs.len() >= 2 {
        let x: Vec<f64> = pairs.iter().map(|p| p.mean).collect();
        let y: Vec<f64> = pairs.iter().map(|p| p.var).collect();
        let wts = vec![1.0; x.len()];
        super::stats::wls_line(&x, &y, &wts)
            .ok()
            .map(|f| [f.slope, f.intercept])
    } else {
        None
    };
    if !(k.is_finite() && k > 0.0) {
        return Err(Error::invalid(format!(
            "ISO {iso}: the flats give a non-positive gain K = {k:e} DN/e- (flat variance not above the dark variance)"
        )));
    }
    Ok((k, pairs, free))
}

/// Fit the physics model from dark and flat frames (any ISOs; grouped by Exif ISO).
pub fn fit_physics(darks: &[Named], flats: &[Named], source: &str) -> Result<PhysicsCalibration> {
    let first = darks
        .first()
        .or(flats.first())
        .ok_or_else(|| Error::invalid("no dark or flat frames"))?;
    let same = SameCapture {
        iso: false,
        levels: true,
    };
    for (name, img) in darks.iter().chain(flats) {
        check_same_capture(first.1, img, same)
            .map_err(|e| Error::invalid(format!("{name}: {e}")))?;
    }
    let norm = Normalizer::new(first.1)?;
    if !norm.is_identity() {
        return Err(Error::unsupported(
            "physics noise calibration of frames with a LinearizationTable",
        ));
    }
    let mut by_iso: BTreeMap<u32, (Vec<Named>, Vec<Named>)> = BTreeMap::new();
    for &(name, img) in darks {
        by_iso
            .entry(iso_of(name, img)?)
            .or_default()
            .0
            .push((name, img));
    }
    for &(name, img) in flats {
        by_iso
            .entry(iso_of(name, img)?)
            .or_default()
            .1
            .push((name, img));
    }
    let mut points = Vec::new();
    let mut fits = Vec::new();
    let mut warnings = crate::diagnostics::Diagnostics::new();
    for (iso, (d, f)) in &by_iso {
        if d.len() < MIN_DARK_FRAMES || f.len() < MIN_FLAT_FRAMES {
            return Err(Error::invalid(format!(
                "ISO {iso}: {} dark and {} flat frames; need at least {MIN_DARK_FRAMES} darks and {MIN_FLAT_FRAMES} flats (one pair) per ISO",
                d.len(),
                f.len()
            )));
        }
        let dark = fit_darks(d, &norm)?;
        let (k, pairs, free) = fit_flats(*iso, f, &norm, &dark, &mut warnings)?;
        points.push(PhysicsPoint {
            iso: *iso,
            k,
            sigma_read: dark.sigma_read,
            lambda: dark.lambda,
            gaussian_read: dark.gaussian,
            sigma_row: dark.sigma_row,
        });
        fits.push(IsoFit {
            iso: *iso,
            dark: dark.fit,
            flats: pairs,
            free_line: free,
        });
    }
    let l = &first.1.meta.levels;
    let model = PhysicsModel::new(source, l.black_max(), l.white, points)?;
    Ok(PhysicsCalibration {
        model,
        fits,
        warnings,
    })
}

/// SVG plot of the fit: flat-pair variance against mean per ISO with the fitted lines
/// (`K mu + v0`), and the dark points at `mu = 0`. Needs the `cli` feature (plotters).
#[cfg(feature = "cli")]
pub fn plot_svg(cal: &PhysicsCalibration) -> Result<String> {
    use crate::plot::{svg, Frame};
    use plotters::prelude::*;
    let perr = |e: &dyn std::fmt::Display| Error::invalid(format!("plot: {e}"));
    let xmax = cal
        .fits
        .iter()
        .flat_map(|f| f.flats.iter().map(|p| p.mean))
        .fold(1.0f64, f64::max)
        * 1.05;
    let ymax = cal
        .fits
        .iter()
        .flat_map(|f| f.flats.iter().map(|p| p.var).chain([f.dark.v0]))
        .fold(1.0f64, f64::max)
        * 1.1;
    let frame = Frame {
        size: (640, 420),
        title: "physics noise fit: var(A-B)/2 vs mean above black",
        margin: 10,
        label_areas: (40, 60),
        x: 0.0..xmax,
        y: 0.0..ymax,
        desc: ("mean signal above black (DN)", "variance (DN^2)"),
        labels: (None, None),
        x_formatter: None,
        x_mesh: true,
        legend: Some(SeriesLabelPosition::UpperLeft),
    };
    svg(frame, |chart| {
        for (i, (f, p)) in cal.fits.iter().zip(&cal.model.isos).enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            let line = [(0.0, f.dark.v0), (xmax, f.dark.v0 + p.k * xmax)];
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .map_err(|e| perr(&e))?
                .label(format!(
                    "ISO {}: K {:.3} DN/e-, read {:.2} DN (lambda {:.2}), row {:.2} DN",
                    p.iso, p.k, p.sigma_read, p.lambda, p.sigma_row
                ))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            let pts = f
                .flats
                .iter()
                .map(|q| (q.mean, q.var))
                .chain([(0.0, f.dark.v0)]);
            chart
                .draw_series(pts.map(|c| Circle::new(c, 4, colour.filled())))
                .map_err(|e| perr(&e))?;
        }
        Ok(())
    })
}
