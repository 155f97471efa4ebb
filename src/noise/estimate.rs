//! Single-image Poisson-Gaussian noise estimate (issue 24; SYNTHESIS.md 7): per 2x2 CFA
//! position, `var(y) = S * y + O` on normalized data, measured on the day raw itself, in the
//! spirit of Foi, Trimeche, Katkovnik and Egiazarian, "Practical Poissonian-Gaussian noise
//! modeling and fitting for single-image raw-data", IEEE TIP 17(10), 2008.
//!
//! Each 2x2 position is a quarter-resolution plane. It is cut into non-overlapping 2x2
//! blocks `u00 u01 / u10 u11` (4x4 mosaic sites, one block per position) and each block is
//! transformed by the orthonormal 2-D Haar basis:
//!
//! ```text
//! m = (u00 + u01 + u10 + u11) / 4        approximation: the block's intensity
//! h = (u00 - u01 + u10 - u11) / 2        horizontal detail
//! v = (u00 + u01 - u10 - u11) / 2        vertical detail
//! d = (u00 - u01 - u10 + u11) / 2        diagonal detail: the noise sample
//! ```
//!
//! On a smooth block (signal linear in row and column) `h`, `v`, `d` are pure noise: with
//! independent sites and a variance that is linear in the signal, `d`, `h`, `v` and `m` are
//! uncorrelated, `E[d^2] = S * E[m] + O`, and `d` does not see ramps or edges along rows or
//! columns at all. Three steps, as in Foi et al. (detail coefficients, smoothness selection,
//! level sets, fit):
//!
//! 1. **Pilot** (a subsample of bands): per position and intensity bin of `m` (the level
//!    sets, [`NBINS`] bins over `[BIN_LO, BIN_HI]`), the first quartile of
//!    `t = (h^2 + v^2) / 2` (`t / sigma^2` is Exp(1) on a smooth block) gives a robust
//!    variance `q25(t) / ln(4/3)`; a line through these (weighted, bins above twice the line
//!    dropped as texture) is the pilot `sigma^2(m)`.
//! 2. **Smoothness selection**: a block is smooth when `t <= C_SELECT * pilot(m)` (keeps 95 %
//!    of pure-noise blocks). The selection looks at `h`, `v` only, which are independent of
//!    `d` on smooth blocks, so it rejects texture and steep ramps without biasing the
//!    variance of `d`. Blocks with a clipped site (stored 0, or linearized >= white) are
//!    left out.
//! 3. **Fit**: per bin, `x = mean(m)`, `v = mean(d^2)`, `n` blocks; a weighted least-squares
//!    line `v = S x + O`, weights `n / (2 pred^2)` (the variance of a mean of `n` squared
//!    Gaussians), iterated on the prediction. Clip-aware: bins whose mean lies within
//!    [`CLIP_MARGIN_SIGMAS`] predicted standard deviations of a clipping bound (stored 0
//!    below, white above) are dropped (truncation would bias them), as are bins whose
//!    variance is more than [`OUTLIER_Z`] standard errors from the line (texture the
//!    selection missed), one at a time. Finally the rounding of raw values, `1/12 DN^2`,
//!    is removed from `O` (as `calibrate noise` does), so that a synthesizer that adds
//!    `N(0, S y + O)` and rounds reproduces the measured variance.
//!
//! A fit is *trusted* only when every position has enough smooth blocks ([`MIN_BLOCKS`])
//! in enough bins ([`MIN_BINS`]) spread over enough intensity ([`MIN_SPAN`]), a positive
//! slope known to [`MAX_REL_SE_S`], and an intercept that is not significantly negative;
//! otherwise [`NoiseEstimate::trusted`] says why. Nothing here is NaN: degenerate frames
//! (1x1, constant, all black, all saturated) are untrusted fits.
//!
//! Every `step`-th band of 4 mosaic rows is read ([`EstimateOptions::step`]); bands are
//! summed in fixed chunks and the chunks in order, so the result is the same for any thread
//! count. Accuracy and cost: docs/noise.md, "Estimated from the day image".

use super::model::NoiseParams;
use crate::error::Result;
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::{Bayer, RawImage};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Intensity bins (level sets) per position.
pub const NBINS: usize = 128;
/// Lower edge of the binned normalized intensity.
pub const BIN_LO: f64 = -1.0 / 32.0;
/// Upper edge of the binned normalized intensity.
pub const BIN_HI: f64 = 1.0;
/// `q25(Exp(1)) = ln(4/3)`: the pilot variance is `q25(t) / PILOT_Q25`.
const PILOT_Q25: f64 = 0.287_682_072_451_780_9;
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
/// Pilot bands aimed at (evenly spaced among the bands read).
const PILOT_BANDS: usize = 96;
/// Bands per chunk of the parallel passes (fixed, for thread-count independent sums).
const CHUNK_BANDS: usize = 16;

/// Options of [`estimate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EstimateOptions {
    /// Read one band of 4 mosaic rows out of every `step` (1 = every band); None = the
    /// default, [`default_step`] (about [`SITES_BUDGET`] sites read).
    pub step: Option<usize>,
}

/// Sites the default subsample reads at most (about): a 12 MP frame reads every second
/// band (docs/noise.md gives the error and cost of each step).
pub const SITES_BUDGET: usize = 6_000_000;

/// The default step for an active area of `sites` sites: `ceil(sites / SITES_BUDGET)`, at
/// least 1.
pub fn default_step(sites: usize) -> usize {
    sites.div_ceil(SITES_BUDGET).max(1)
}

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

/// The estimate of an image: one fit per 2x2 position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseEstimate {
    /// Bands of 4 rows read: one of every `step`.
    pub step: usize,
    /// Rounding variance removed from each intercept, normalized units (`1 / (12 scale^2)`).
    pub quantization_variance_removed: f64,
    /// The four positions.
    pub positions: Vec<PositionEstimate>,
}

impl NoiseEstimate {
    /// The parameters when every position's fit can be trusted, else the first reason why
    /// not (naming the position).
    pub fn trusted(&self) -> std::result::Result<NoiseParams, String> {
        let mut positions = [[0.0; 2]; 4];
        for (p, out) in self.positions.iter().zip(positions.iter_mut()) {
            if let Some(why) = &p.problem {
                return Err(format!("position {} ({}): {}", p.position, p.color, why));
            }
            *out = [p.s, p.o];
        }
        if self.positions.len() != 4 {
            return Err("no positions fitted".into());
        }
        Ok(NoiseParams { positions })
    }

    /// Smooth blocks over all positions.
    pub fn smooth_blocks(&self) -> u64 {
        self.positions.iter().map(|p| p.smooth_blocks).sum()
    }
}

/// Per position and bin: sums of the smooth blocks (pass 2).
#[derive(Clone, Copy, Default)]
struct Acc {
    n: u64,
    sm: f64,
    sd2: f64,
}

/// Sums of one chunk of bands.
#[derive(Clone)]
struct Sums {
    bins: Vec<[Acc; NBINS]>,
    blocks: [u64; 4],
    clipped: [u64; 4],
}

impl Sums {
    fn new() -> Sums {
        Sums {
            bins: vec![[Acc::default(); NBINS]; 4],
            blocks: [0; 4],
            clipped: [0; 4],
        }
    }
    fn add(&mut self, o: &Sums) {
        for (a, b) in self.bins.iter_mut().zip(&o.bins) {
            for (x, y) in a.iter_mut().zip(b) {
                x.n += y.n;
                x.sm += y.sm;
                x.sd2 += y.sd2;
            }
        }
        for p in 0..4 {
            self.blocks[p] += o.blocks[p];
            self.clipped[p] += o.clipped[p];
        }
    }
}

#[inline]
fn bin_of(m: f64) -> Option<usize> {
    let t = (m - BIN_LO) / (BIN_HI - BIN_LO) * NBINS as f64;
    (t >= 0.0 && t < NBINS as f64).then_some(t as usize)
}

/// One block of one position: intensity `m` (NaN when a site is clipped), `h^2 + v^2` and
/// `d^2`.
#[derive(Clone, Copy)]
struct Block {
    m: f64,
    hv2: f64,
    d2: f64,
}

/// 95 % quantiles of `chi2(k) / k`, k = 0..=26 (entries below 2 unused): a smooth block's
/// local variance over `k` detail coefficients stays below `Q95[k] * sigma^2` with
/// probability 95 %.
const Q95: [f64; 27] = [
    f64::INFINITY,
    f64::INFINITY,
    2.9957322735539895,
    2.6049093010837265,
    2.3719322591952885,
    2.2140995387032705,
    2.0985978739573294,
    2.009591492762881,
    1.9384141319831814,
    1.879886400513383,
    1.8307038053275146,
    1.7886488702438628,
    1.7521724847902558,
    1.720156345755918,
    1.6917708074886126,
    1.666386009315241,
    1.6435142253040145,
    1.6227712728397259,
    1.6038499683551457,
    1.5865014318761137,
    1.570521642211546,
    1.5557415876627292,
    1.542019930520173,
    1.5292374620394809,
    1.5172928542419715,
    1.5060993653393109,
    1.4955822561473098,
];

/// Blocks on each side of a block whose details enter its local variance.
const NEIGHBOURS: usize = 4;

/// The frame being read: normalizer and active-area geometry.
struct Frame<'a> {
    img: &'a RawImage,
    norm: Normalizer,
    /// The normalized value (NaN when clipped) of every stored value up to white per 2x2
    /// position, when the black level depends on the position only.
    table: Option<SiteTable<f64>>,
    top: usize,
    left: usize,
    /// Bands of 4 active rows and groups of 4 active columns.
    bands: usize,
    groups: usize,
}

/// Scratch space of one band: normalized rows, black levels, blocks per position.
#[derive(Default)]
struct BandBuf {
    rows: [Vec<f64>; 4],
    black: Vec<f64>,
    blocks: [Vec<Block>; 4],
}

/// The normalized value of stored value `x` on a site of black level `black`
/// ([`Normalizer::normalize_with_black`]), NaN when the site is clipped (stored 0 or
/// linearized at or above white).
#[inline]
fn site(norm: &Normalizer, x: u16, black: f64) -> f64 {
    if x == 0 || norm.linearize(x) >= norm.white {
        f64::NAN
    } else {
        norm.normalize_with_black(x, black)
    }
}

impl Frame<'_> {
    /// The blocks of band `k` (4 active rows), per position, into `buf.blocks`.
    fn band(&self, k: usize, buf: &mut BandBuf) {
        let w = self.groups * 4;
        for (i, row) in buf.rows.iter_mut().enumerate() {
            let r = 4 * k + i;
            row.resize(w, 0.0);
            let start = (r + self.top) * self.img.width + self.left;
            let src = &self.img.data[start..start + w];
            match &self.table {
                Some(t) => {
                    let (even, odd) = t.row(r);
                    for (c, (o, &x)) in row.iter_mut().zip(src).enumerate() {
                        let tab = if c & 1 == 0 { even } else { odd };
                        *o = match tab.get(x as usize) {
                            Some(&v) => v,
                            None => site(&self.norm, x, self.norm.black_at(r, c)),
                        };
                    }
                }
                None => {
                    buf.black.resize(w, 0.0);
                    self.norm.black_row(r, &mut buf.black);
                    for ((o, &x), &b) in row.iter_mut().zip(src).zip(buf.black.iter()) {
                        *o = site(&self.norm, x, b);
                    }
                }
            }
        }
        let rows = &buf.rows;
        for (pos, out) in buf.blocks.iter_mut().enumerate() {
            let (pr, pc) = (pos >> 1, pos & 1);
            out.clear();
            out.extend((0..self.groups).map(|g| {
                let c0 = 4 * g + pc;
                let u00 = rows[pr][c0];
                let u01 = rows[pr][c0 + 2];
                let u10 = rows[pr + 2][c0];
                let u11 = rows[pr + 2][c0 + 2];
                let h = (u00 - u01 + u10 - u11) * 0.5;
                let v = (u00 + u01 - u10 - u11) * 0.5;
                let d = (u00 - u01 - u10 + u11) * 0.5;
                Block {
                    m: (u00 + u01 + u10 + u11) * 0.25,
                    hv2: h * h + v * v,
                    d2: d * d,
                }
            }));
        }
    }
}

/// Prefix sums over a band's blocks of `h^2 + v^2 + d^2` and of the unclipped blocks, for
/// [`local_variance`] in constant time.
fn prefix(blocks: &[Block], sums: &mut Vec<f64>, counts: &mut Vec<u32>) {
    sums.clear();
    counts.clear();
    let (mut s, mut c) = (0.0, 0u32);
    sums.push(s);
    counts.push(c);
    for b in blocks {
        if !b.m.is_nan() {
            s += b.hv2 + b.d2;
            c += 1;
        }
        sums.push(s);
        counts.push(c);
    }
}

/// The local variance around unclipped block `g` of a band: the mean square of its own `h`,
/// `v` and of the `h`, `v`, `d` of the unclipped blocks among the [`NEIGHBOURS`] on each
/// side (never its own `d`, so that selecting on it does not bias `d`), with its number of
/// terms. `sums`, `counts`: [`prefix`] of the band.
#[inline]
fn local_variance(blocks: &[Block], sums: &[f64], counts: &[u32], g: usize) -> (f64, usize) {
    let lo = g.saturating_sub(NEIGHBOURS);
    let hi = (g + NEIGHBOURS + 1).min(blocks.len());
    let sum = (sums[hi] - sums[lo] - blocks[g].d2).max(0.0);
    let k = 3 * (counts[hi] - counts[lo]) as usize - 1;
    (sum / k as f64, k)
}

/// The pilot variance per position: a line `a m + b` (None when it could not be fitted),
/// floored at half the smallest positive per-bin value (a line crossing zero in the dark
/// would select nothing there), and the per-bin first-quartile variances it was fitted to.
#[derive(Clone, Debug)]
struct Pilot {
    line: Option<(f64, f64)>,
    floor: f64,
    per_bin: Vec<Option<f64>>,
}

impl Pilot {
    /// The pilot variance at intensity `m` in bin `b` (None: no pilot there).
    #[inline]
    fn at(&self, m: f64, b: usize) -> Option<f64> {
        match self.line {
            Some((a, c)) => Some((a * m + c).max(self.floor)),
            None => self.per_bin[b],
        }
    }
}

fn fit_pilot(samples: &mut [Vec<f32>]) -> Pilot {
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
struct Line {
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
fn irls_line(pts: &[(f64, f64, f64)], iters: usize) -> Option<Line> {
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

/// Estimate the noise of `img` (see the module documentation). Errors only when the image
/// cannot be normalized or is not a Bayer mosaic; an estimate that cannot be trusted is a
/// result ([`NoiseEstimate::trusted`]).
pub fn estimate(img: &RawImage, opts: &EstimateOptions) -> Result<NoiseEstimate> {
    let bayer = img.bayer()?;
    let norm = Normalizer::new(img)?;
    let a = img.active_area();
    let table = SiteTable::new(&norm, |r, c, x| site(&norm, x, norm.black_at(r, c)));
    let frame = Frame {
        img,
        table,
        top: a.top as usize,
        left: a.left as usize,
        bands: a.height() / 4,
        groups: a.width() / 4,
        norm,
    };
    let step = opts
        .step
        .unwrap_or_else(|| default_step(a.width() * a.height()))
        .max(1);
    let bands: Vec<usize> = (0..frame.bands).step_by(step).collect();
    let pilot_stride = bands.len().div_ceil(PILOT_BANDS).max(1);
    let pilot_bands: Vec<usize> = bands.iter().copied().step_by(pilot_stride).collect();

    // Pass 1: smoothness statistics t = (h^2 + v^2) / 2 of the pilot bands, per position
    // and bin.
    let chunks: Vec<Vec<Vec<f32>>> = pilot_bands
        .par_chunks(CHUNK_BANDS)
        .map(|ch| {
            let mut t = vec![Vec::new(); 4 * NBINS];
            let mut buf = BandBuf::default();
            for &k in ch {
                frame.band(k, &mut buf);
                for (pos, blocks) in buf.blocks.iter().enumerate() {
                    for b in blocks {
                        if let Some(i) = bin_of(b.m) {
                            t[pos * NBINS + i].push((b.hv2 * 0.5) as f32);
                        }
                    }
                }
            }
            t
        })
        .collect();
    let mut t_all = vec![Vec::new(); 4 * NBINS];
    for c in chunks {
        for (a, b) in t_all.iter_mut().zip(c) {
            a.extend(b);
        }
    }
    let pilots: Vec<Pilot> = t_all.chunks_mut(NBINS).map(fit_pilot).collect();

    // Pass 2: smooth blocks of every band read.
    let sums: Vec<Sums> = bands
        .par_chunks(CHUNK_BANDS)
        .map(|ch| {
            let mut s = Sums::new();
            let mut buf = BandBuf::default();
            let (mut sums, mut counts) = (Vec::new(), Vec::new());
            for &k in ch {
                frame.band(k, &mut buf);
                for (pos, blocks) in buf.blocks.iter().enumerate() {
                    prefix(blocks, &mut sums, &mut counts);
                    for (g, b) in blocks.iter().enumerate() {
                        if b.m.is_nan() {
                            s.clipped[pos] += 1;
                            continue;
                        }
                        let Some(i) = bin_of(b.m) else { continue };
                        s.blocks[pos] += 1;
                        let Some(p) = pilots[pos].at(b.m, i) else {
                            continue;
                        };
                        let (local, terms) = local_variance(blocks, &sums, &counts, g);
                        if local <= Q95[terms] * p {
                            let acc = &mut s.bins[pos][i];
                            acc.n += 1;
                            acc.sm += b.m;
                            acc.sd2 += b.d2;
                        }
                    }
                }
            }
            s
        })
        .collect();
    let mut total = Sums::new();
    for s in &sums {
        total.add(s);
    }

    let scale = frame.norm.scale;
    let q = 1.0 / (12.0 * scale * scale);
    // Clipping bounds per position: stored 0 below, white above (the nearest over the plane).
    let positions = (0..4)
        .map(|pos| {
            let lo = -(0..2)
                .flat_map(|r| (0..2).map(move |c| (r, c)))
                .filter(|&(r, c)| Bayer::position(r, c) == pos)
                .map(|(r, c)| frame.norm.black_at(r, c))
                .fold(f64::INFINITY, f64::min)
                / scale;
            let lo = if lo.is_finite() { lo } else { 0.0 };
            let hi = 1.0;
            fit_position(
                pos,
                bayer,
                &total.bins[pos],
                total.blocks[pos],
                total.clipped[pos],
                (lo, hi),
                q,
            )
        })
        .collect();
    Ok(NoiseEstimate {
        step,
        quantization_variance_removed: q,
        positions,
    })
}

fn colour_name(c: u8) -> &'static str {
    match c {
        0 => "R",
        1 => "G",
        _ => "B",
    }
}

/// The robust, clip-aware line through one position's bins, and its verdict.
fn fit_position(
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
    let problem = verdict(
        line.is_some(),
        smooth_blocks,
        fitted.len(),
        span,
        s,
        s_se,
        intercept,
        o_se,
        fitted.iter().all(|b| b.var == 0.0),
    );
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

/// Why a position's fit cannot be trusted (None when it can).
#[allow(clippy::too_many_arguments)]
fn verdict(
    fitted: bool,
    smooth_blocks: u64,
    bins: usize,
    span: [f64; 2],
    s: f64,
    s_se: f64,
    intercept: f64,
    o_se: f64,
    all_zero: bool,
) -> Option<String> {
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
    use crate::raw::meta::RawMeta;

    fn frame(w: usize, h: usize, f: impl Fn(usize, usize) -> u16) -> RawImage {
        let meta = RawMeta::new_bayer(Bayer::RGGB, 12, 64.0, 4095.0);
        RawImage {
            width: w,
            height: h,
            data: (0..w * h).map(|i| f(i / w, i % w)).collect(),
            meta,
        }
    }

    #[test]
    fn degenerate_frames_are_untrusted_and_finite() {
        let cases = [
            ("1x1", frame(1, 1, |_, _| 100)),
            ("3x5", frame(5, 3, |r, c| (100 + r * 7 + c) as u16)),
            ("black", frame(64, 64, |_, _| 64)),
            ("zero", frame(64, 64, |_, _| 0)),
            ("saturated", frame(64, 64, |_, _| 4095)),
            ("constant", frame(200, 200, |_, _| 1000)),
        ];
        for (name, img) in cases {
            let e = estimate(&img, &EstimateOptions::default()).unwrap();
            let why = e.trusted().unwrap_err();
            assert!(!why.is_empty(), "{name}");
            for p in &e.positions {
                for v in [
                    p.s,
                    p.o,
                    p.intercept,
                    p.s_stderr,
                    p.o_stderr,
                    p.span[0],
                    p.span[1],
                ] {
                    assert!(v.is_finite(), "{name}: {p:?}");
                }
            }
        }
    }

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
