//! The fitting half of the single-image noise estimate ([`super::estimate`](mod@super::estimate)): the pilot
//! variance line, the robust clip-aware weighted line through a position's level sets, the
//! verdict on whether it can be trusted, and the per-position result types. The
//! algorithm and its accuracy: docs/noise.md, "Estimated from the day image".

use crate::raw::Bayer;
use serde::{Deserialize, Serialize};

/// Intensity bins (level sets) per position.
pub const NBINS: usize = 128;
/// Lower edge of the binned normalized intensity.
pub const BIN_LO: f64 = -1.0 / 32.0;
/// Upper edge of the binned normalized intensity.
pub const BIN_HI: f64 = 1.0;
/// `q25(Exp(1)) = ln(4/3)`: the pilot variance is `q25(t) / PILOT_Q25`.
pub(super) const PILOT_Q25: f64 = 0.287_682_072_451_780_9;
/// Fewest pilot samples for a bin's pilot variance.
const MIN_PILOT_SAMPLES: usize = 16;
/// Fewest smooth blocks for a bin to enter the fit.
pub const MIN_BIN_BLOCKS: u64 = 32;
/// Fewest smooth blocks per position for a trusted fit.
pub const MIN_BLOCKS: u64 = 1000;
/// Fewest bins per position for a trusted fit.
pub const MIN_BINS: usize = 3;
/// Smallest intensity span (normalized) of the fitted bins for a trusted fit.
pub const MIN_SPAN: f64 = 0.05;
/// Largest relative standard error of `S` for a trusted fit.
pub const MAX_REL_SE_S: f64 = 0.25;
/// Bins within this many predicted standard deviations of a clipping bound are dropped.
pub const CLIP_MARGIN_SIGMAS: f64 = 4.0;
/// Bins further than this many standard errors from the line are dropped as outliers.
pub const OUTLIER_Z: f64 = 6.0;

/// One intensity bin of one position: smooth blocks, mean intensity and mean `d^2`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct EstimateBin {
    /// Mean normalized intensity `mean(m)`.
    pub mean: f64,
    /// Mean squared diagonal detail `mean(d^2)` (normalized units squared).
    pub var: f64,
    /// Smooth blocks.
    pub blocks: u64,
}

/// The fit of one 2x2 position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PositionEstimate {
    /// 2x2 position, row-major relative to the ActiveArea origin.
    pub position: usize,
    /// CFA colour there: "R", "G" or "B".
    pub color: String,
    /// Shot parameter `S` (normalized; 0 when no line could be fitted).
    #[serde(rename = "S")]
    pub s: f64,
    /// Read parameter `O`, rounding variance removed, at least 0.
    #[serde(rename = "O")]
    pub o: f64,
    /// Fitted intercept before the rounding variance was removed (may be negative).
    pub intercept: f64,
    /// Standard error of `S`.
    pub s_stderr: f64,
    /// Standard error of the intercept.
    pub o_stderr: f64,
    /// Blocks examined (no clipped site, intensity within the bins).
    pub blocks: u64,
    /// Of them, smooth blocks in the fitted bins.
    pub smooth_blocks: u64,
    /// Blocks left out because a site was clipped.
    pub clipped_blocks: u64,
    /// Bins fitted.
    pub bins: usize,
    /// Intensity range of the fitted bins.
    pub span: [f64; 2],
    /// Why this fit cannot be trusted (None = trusted).
    pub problem: Option<String>,
    /// The bins (all non-empty ones; `fitted` says which entered the line).
    #[serde(skip)]
    pub level_sets: Vec<(EstimateBin, bool)>,
}

/// Per position and bin: sums of the smooth blocks (pass 2).
#[derive(Clone, Copy, Default)]
pub(super) struct Acc {
    pub(super) n: u64,
    pub(super) sm: f64,
    pub(super) sd2: f64,
}

/// The pilot variance per position: a line `a m + b` (None when it could not be fitted),
/// floored at half the smallest positive per-bin value (a line crossing zero in the dark
/// would select nothing there), and the per-bin first-quartile variances it was fitted to.
#[derive(Clone, Debug)]
pub(super) struct Pilot {
    line: Option<(f64, f64)>,
    floor: f64,
    per_bin: Vec<Option<f64>>,
}

impl Pilot {
    /// The pilot variance at intensity `m` in bin `b` (None: no pilot there).
    #[inline]
    pub(super) fn at(&self, m: f64, b: usize) -> Option<f64> {
        match self.line {
            Some((a, c)) => Some((a * m + c).max(self.floor)),
            None => self.per_bin[b],
        }
    }
}

pub(super) fn fit_pilot(samples: &mut [Vec<f32>]) -> Pilot {
    let mut per_bin = vec![None; NBINS];
    let mut pts = Vec::new();
    for (b, s) in samples.iter_mut().enumerate() {
        if s.len() < MIN_PILOT_SAMPLES {
            continue;
        }
        let k = s.len() / 4;
        let (_, q, _) = s.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
        let var = *q as f64 / PILOT_Q25;
        per_bin[b] = Some(var);
        let x = BIN_LO + (b as f64 + 0.5) * (BIN_HI - BIN_LO) / NBINS as f64;
        pts.push((x, var, s.len() as f64));
    }
    // A line through the robust per-bin values; bins far above it are texture.
    let mut keep = vec![true; pts.len()];
    let mut line = None;
    for _ in 0..4 {
        let sel: Vec<(f64, f64, f64)> = pts
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(p, _)| *p)
            .collect();
        let Some(l) = irls_line(&sel, 3) else { break };
        line = Some((l.slope, l.intercept));
        let mut changed = false;
        for (p, k) in pts.iter().zip(keep.iter_mut()) {
            let pred = l.slope * p.0 + l.intercept;
            if *k && pred > 0.0 && p.1 > 2.0 * pred {
                *k = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let floor = per_bin
        .iter()
        .flatten()
        .copied()
        .filter(|&x| x > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { 0.5 * floor } else { 0.0 };
    Pilot {
        line,
        floor,
        per_bin,
    }
}

/// A weighted straight line `v = slope * x + intercept` with standard errors.
#[derive(Debug, Clone, Copy)]
pub(super) struct Line {
    slope: f64,
    intercept: f64,
    slope_se: f64,
    intercept_se: f64,
    /// Reduced chi-square of the last iteration.
    chi2_dof: f64,
}

/// Weighted least squares of points `(x, v, n)` with weights `n / (2 pred^2)`, iterated
/// `iters` times on the prediction (the first with the measured `v`). None with fewer than
/// two usable points or coinciding `x`.
pub(super) fn irls_line(pts: &[(f64, f64, f64)], iters: usize) -> Option<Line> {
    if pts.len() < 2 {
        return None;
    }
    let vmax = pts.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    // Predictions are floored so that a zero (noise-free) bin cannot get an infinite weight.
    let floor = (vmax * 1e-3).max(1e-300);
    let mut pred: Vec<f64> = pts.iter().map(|p| p.1.max(floor)).collect();
    let mut out = None;
    for _ in 0..iters.max(1) {
        let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let mut ws = Vec::with_capacity(pts.len());
        for (p, &pr) in pts.iter().zip(&pred) {
            let w = p.2 / (2.0 * pr * pr);
            ws.push(w);
            sw += w;
            sx += w * p.0;
            sy += w * p.1;
        }
        if !(sw > 0.0 && sw.is_finite()) {
            return out;
        }
        let (xm, ym) = (sx / sw, sy / sw);
        for (p, &w) in pts.iter().zip(&ws) {
            sxx += w * (p.0 - xm) * (p.0 - xm);
            sxy += w * (p.0 - xm) * (p.1 - ym);
        }
        if !(sxx > 0.0 && sxx.is_finite()) {
            return out;
        }
        let slope = sxy / sxx;
        let intercept = ym - slope * xm;
        let mut chi2 = 0.0;
        for (p, &w) in pts.iter().zip(&ws) {
            let r = p.1 - slope * p.0 - intercept;
            chi2 += w * r * r;
        }
        let dof = pts.len().saturating_sub(2).max(1) as f64;
        let chi2_dof = chi2 / dof;
        if !(slope.is_finite() && intercept.is_finite()) {
            return out;
        }
        out = Some(Line {
            slope,
            intercept,
            slope_se: (1.0 / sxx).sqrt(),
            intercept_se: (1.0 / sw + xm * xm / sxx).sqrt(),
            chi2_dof,
        });
        for (p, pr) in pts.iter().zip(pred.iter_mut()) {
            *pr = (slope * p.0 + intercept).max(floor);
        }
    }
    out
}

fn colour_name(c: u8) -> &'static str {
    match c {
        0 => "R",
        1 => "G",
        _ => "B",
    }
}

/// The robust, clip-aware line through one position's bins, and its verdict.
pub(super) fn fit_position(
    pos: usize,
    bayer: Bayer,
    bins: &[Acc; NBINS],
    blocks: u64,
    clipped_blocks: u64,
    (lo, hi): (f64, f64),
    q: f64,
) -> PositionEstimate {
    let all: Vec<EstimateBin> = bins
        .iter()
        .filter(|a| a.n > 0)
        .map(|a| EstimateBin {
            mean: a.sm / a.n as f64,
            var: a.sd2 / a.n as f64,
            blocks: a.n,
        })
        .collect();
    let mut use_bin: Vec<bool> = all.iter().map(|b| b.blocks >= MIN_BIN_BLOCKS).collect();
    let pts = |use_bin: &[bool]| -> Vec<(f64, f64, f64)> {
        all.iter()
            .zip(use_bin)
            .filter(|(_, u)| **u)
            .map(|(b, _)| (b.mean, b.var, b.blocks as f64))
            .collect()
    };
    let mut line = irls_line(&pts(&use_bin), 5);
    // Clip margins, then outliers one at a time (at most a quarter of the bins).
    let max_drops = use_bin.iter().filter(|u| **u).count() / 4;
    let mut drops = 0;
    while let Some(l) = line {
        let mut changed = false;
        for (b, u) in all.iter().zip(use_bin.iter_mut()) {
            let pred = l.slope * b.mean + l.intercept;
            let sd = pred.max(0.0).sqrt();
            if *u
                && (b.mean - lo < CLIP_MARGIN_SIGMAS * sd || hi - b.mean < CLIP_MARGIN_SIGMAS * sd)
            {
                *u = false;
                changed = true;
            }
        }
        if !changed && drops < max_drops {
            // The worst standardized residual.
            let worst = all
                .iter()
                .enumerate()
                .filter(|(i, _)| use_bin[*i])
                .map(|(i, b)| {
                    let pred = (l.slope * b.mean + l.intercept).max(f64::MIN_POSITIVE);
                    let z = (b.var - pred) / (pred * (2.0 / b.blocks as f64).sqrt());
                    (i, z.abs())
                })
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((i, z)) = worst {
                if z > OUTLIER_Z {
                    use_bin[i] = false;
                    drops += 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
        line = irls_line(&pts(&use_bin), 5);
    }
    let fitted: Vec<&EstimateBin> = all
        .iter()
        .zip(&use_bin)
        .filter(|(_, u)| **u)
        .map(|(b, _)| b)
        .collect();
    let smooth_blocks: u64 = fitted.iter().map(|b| b.blocks).sum();
    let span = if fitted.is_empty() {
        [0.0, 0.0]
    } else {
        [
            fitted.iter().map(|b| b.mean).fold(f64::INFINITY, f64::min),
            fitted
                .iter()
                .map(|b| b.mean)
                .fold(f64::NEG_INFINITY, f64::max),
        ]
    };
    let (s, intercept, s_se, o_se) = match line {
        Some(l) => {
            // Standard errors widened by the misfit when the bins scatter more than their
            // own statistics say.
            let k = l.chi2_dof.max(1.0).sqrt();
            (l.slope, l.intercept, l.slope_se * k, l.intercept_se * k)
        }
        None => (0.0, 0.0, f64::INFINITY, f64::INFINITY),
    };
    let problem = verdict(&LineFit {
        fitted: line.is_some(),
        smooth_blocks,
        bins: fitted.len(),
        span,
        s,
        s_se,
        intercept,
        o_se,
        all_zero: fitted.iter().all(|b| b.var == 0.0),
    });
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    PositionEstimate {
        position: pos,
        color: colour_name(bayer.0[pos]).into(),
        s: finite(s),
        o: finite((intercept - q).max(0.0)),
        intercept: finite(intercept),
        s_stderr: if s_se.is_finite() { s_se } else { f64::MAX },
        o_stderr: if o_se.is_finite() { o_se } else { f64::MAX },
        blocks,
        smooth_blocks,
        clipped_blocks,
        bins: fitted.len(),
        span,
        problem,
        level_sets: all.into_iter().zip(use_bin).collect(),
    }
}

/// What [`verdict`] judges of one position's line fit.
struct LineFit {
    /// A line could be fitted.
    fitted: bool,
    /// Blocks in the bins the line was fitted to.
    smooth_blocks: u64,
    /// Bins the line was fitted to.
    bins: usize,
    /// Lowest and highest mean of those bins.
    span: [f64; 2],
    /// Slope and its standard error.
    s: f64,
    s_se: f64,
    /// Intercept (O before the quantization correction) and its standard error.
    intercept: f64,
    o_se: f64,
    /// Every fitted bin has variance 0.
    all_zero: bool,
}

/// Why a position's fit cannot be trusted (None when it can).
fn verdict(fit: &LineFit) -> Option<String> {
    let &LineFit {
        fitted,
        smooth_blocks,
        bins,
        span,
        s,
        s_se,
        intercept,
        o_se,
        all_zero,
    } = fit;
    if smooth_blocks < MIN_BLOCKS || bins < MIN_BINS {
        return Some(format!(
            "too few smooth samples: {smooth_blocks} smooth 2x2 blocks in {bins} intensity \
             levels (need {MIN_BLOCKS} in {MIN_BINS})"
        ));
    }
    if all_zero {
        return Some("no noise: the smooth samples do not vary at all".into());
    }
    if span[1] - span[0] < MIN_SPAN {
        return Some(format!(
            "the smooth samples cover too narrow an intensity range ({:.3} to {:.3}, need \
             {MIN_SPAN}) to tell shot from read noise",
            span[0], span[1]
        ));
    }
    if !fitted {
        return Some("no line could be fitted".into());
    }
    if s <= 0.0 {
        return Some(format!(
            "negative slope (S = {s:.3e}): the variance does not grow with the signal"
        ));
    }
    if s_se > MAX_REL_SE_S * s {
        return Some(format!(
            "the slope is too uncertain (S = {s:.3e} +- {s_se:.1e}, more than {:.0} %)",
            MAX_REL_SE_S * 100.0
        ));
    }
    if intercept + 3.0 * o_se < 0.0 {
        return Some(format!(
            "negative read noise (O = {intercept:.3e} +- {o_se:.1e}): the variance is below \
             zero at black"
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn irls_recovers_an_exact_line() {
        let pts: Vec<(f64, f64, f64)> = (0..10)
            .map(|i| {
                let x = i as f64 * 0.1;
                (x, 2e-4 * x + 1e-6, 100.0)
            })
            .collect();
        let l = irls_line(&pts, 5).unwrap();
        assert!((l.slope - 2e-4).abs() < 1e-12 && (l.intercept - 1e-6).abs() < 1e-14);
        assert!(irls_line(&pts[..1], 5).is_none());
        let same_x = [(0.5, 1.0, 10.0), (0.5, 2.0, 10.0)];
        assert!(irls_line(&same_x, 5).is_none());
    }

    #[test]
    fn pilot_quartile_constant() {
        assert!((PILOT_Q25 - (4.0f64 / 3.0).ln()).abs() < 1e-15);
    }
}
