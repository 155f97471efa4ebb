//! Single-image Poisson-Gaussian noise estimate (issue 24; docs/noise.md): per 2x2 CFA
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

use super::estimate_fit::{fit_pilot, fit_position, Acc, Pilot};
pub use super::estimate_fit::{
    EstimateBin, PositionEstimate, BIN_HI, BIN_LO, CLIP_MARGIN_SIGMAS, MAX_REL_SE_S, MIN_BINS,
    MIN_BIN_BLOCKS, MIN_BLOCKS, MIN_SPAN, NBINS, OUTLIER_Z,
};
use super::model::NoiseParams;
use crate::error::Result;
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::{Bayer, RawImage};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

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
}
