//! Noise model calibration (docs/synthesis.md, "7. Noise"; docs/calibration.md): per ISO and per 2x2 CFA position, the
//! heteroscedastic model `var(y) = S * y + O` on normalized data.
//!
//! - From a burst (aligned frames of a static scene, same ISO and exposure): per pixel the
//!   mean and unbiased variance across frames (exact integer sums), from linearized values
//!   normalized WITHOUT clipping negatives. Split-half binning: the frames are split into
//!   even and odd ones; a pixel is binned by the mean of one half and contributes the mean
//!   and variance of the OTHER half (both ways round). Binning by the same noisy mean that is
//!   regressed on would shrink dark bins toward the dense part of the intensity histogram
//!   (about +10 % on O for a dark night scene and 8 frames); with independent halves the
//!   bin's expected variance is exactly `S * E[x | bin] + O`. A burst therefore needs at least
//!   4 frames (2 per half); measured on a dark ramp, the unsplit estimator on 2-3 frames
//!   overestimated O by 35-60 %, so it is refused rather than offered.
//! - From a pair (clean = e.g. a merged long burst, noisy = one frame): the residual
//!   `noisy - clean` per pixel, its variance per intensity bin of the clean value, the bin's
//!   intensity being the mean of the noisy values (unaffected by the binning).
//!
//! Pixels with any clipped sample (stored 0 or linearized >= white) are excluded. Pixels are
//! binned by intensity (256 bins over normalized [-0.1, 1.05]); each bin gives a point (mean
//! intensity, mean variance, degrees of freedom). S and O come from weighted least squares
//! with weights `dof / (2 v^2)` (the variance of a variance estimate), iterated with `v` the
//! model prediction; bins whose mean lies within 4 predicted standard deviations of a
//! clipping bound are dropped (truncation would bias them). Goodness of fit: weighted R^2 and
//! reduced chi-square. Finally the rounding of raw values (variance 1/12 DN^2) is removed from
//! O, so that a synthesizer that adds `N(0, S y + O)` and rounds reproduces the measured
//! variance.

use super::format::{IsoLaws, IsoModel, NoiseModelFile, PositionFit, NOISE_FORMAT, NOISE_UNITS};
use super::stats::{ls_through_origin, wls_line, LineFit};
use super::{check_same_capture, SameCapture};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::noise::model::NoiseParams;
use crate::normalize::Normalizer;
use crate::raw::camera::CameraId;
use crate::raw::{Bayer, RawImage};
use std::collections::BTreeMap;

/// Fewest frames in a burst (two per half of the split-half estimator).
pub const MIN_BURST_FRAMES: usize = 4;
/// Number of intensity bins.
pub const NBINS: usize = 256;
/// Lower edge of the binned normalized range.
pub const BIN_LO: f64 = -0.1;
/// Upper edge of the binned normalized range.
pub const BIN_HI: f64 = 1.05;
/// Bins with fewer pixels are ignored.
pub const MIN_BIN_PIXELS: u64 = 16;
/// Bins with fewer degrees of freedom are ignored.
pub const MIN_BIN_DOF: f64 = 64.0;
/// Distance (in predicted standard deviations) a bin must keep from a clipping bound.
pub const CLIP_MARGIN_SIGMAS: f64 = 4.0;

/// One intensity bin of one 2x2 position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BinStat {
    /// Mean normalized intensity of the bin's pixels.
    pub mean: f64,
    /// Mean variance (normalized units squared).
    pub var: f64,
    /// Degrees of freedom of `var`.
    pub dof: f64,
    /// Pixels in the bin.
    pub pixels: u64,
}

/// Binned statistics of one source (a burst or a pair).
#[derive(Debug, Clone)]
pub struct SourceStats {
    /// "burst" or "pair".
    pub kind: &'static str,
    /// Exif ISO.
    pub iso: u32,
    /// Bayer pattern of the active area.
    pub bayer: Bayer,
    /// Black (max over the plane), DN.
    pub black: f64,
    /// White level, DN.
    pub white: f64,
    /// Camera description.
    pub camera: Option<String>,
    /// Bins per 2x2 position (only non-empty bins).
    pub bins: [Vec<BinStat>; 4],
    /// Pixels excluded for clipping, per position.
    pub clipped: [u64; 4],
    /// Frames in the burst (2 for a pair).
    pub frames: usize,
}

impl SourceStats {
    fn scale(&self) -> f64 {
        self.white - self.black
    }
    /// Normalized clipping bounds: stored 0 and the white level.
    fn bounds(&self) -> (f64, f64) {
        (-self.black / self.scale(), 1.0)
    }
}

fn iso_of(img: &RawImage) -> Result<u32> {
    img.meta.exif.iso.filter(|&i| i > 0).ok_or_else(|| {
        Error::invalid(
            "the frame has no Exif ISO: the noise model is indexed by ISO (calibrate noise --assume-iso N gives one)",
        )
    })
}

fn camera_of(img: &RawImage) -> Option<String> {
    let m = &img.meta;
    m.unique_camera_model
        .clone()
        .or_else(|| match (&m.make, &m.model) {
            (Some(a), Some(b)) => Some(format!("{a} {b}")),
            (a, b) => a.clone().or(b.clone()),
        })
}

#[inline]
fn bin_index(y: f64) -> Option<usize> {
    let t = (y - BIN_LO) / (BIN_HI - BIN_LO) * NBINS as f64;
    (t >= 0.0 && t < NBINS as f64).then_some(t as usize)
}

#[derive(Clone, Copy, Default)]
struct Acc {
    n: u64,
    sy: f64,
    sv: f64,
    sr: f64,
    srr: f64,
}

/// Streaming per-pixel statistics of a burst: frames are added one at a time.
#[derive(Debug)]
pub struct BurstAccumulator {
    first: RawImage,
    norm: Normalizer,
    frames: usize,
    /// Per pixel, per half (even/odd frames): sum and sum of squares of linearized values.
    sums: Vec<[u64; 4]>,
    clipped: Vec<bool>,
}

impl BurstAccumulator {
    /// Start with the first frame.
    pub fn new(first: RawImage) -> Result<Self> {
        let norm = Normalizer::new(&first)?;
        first.bayer()?;
        iso_of(&first)?;
        let a = first.active_area();
        let n = a.width() * a.height();
        let mut acc = BurstAccumulator {
            norm,
            frames: 0,
            sums: vec![[0; 4]; n],
            clipped: vec![false; n],
            first: RawImage {
                width: first.width,
                height: first.height,
                data: vec![],
                meta: first.meta.clone(),
            },
        };
        acc.add_unchecked(&first);
        acc.first.data = first.data;
        Ok(acc)
    }

    /// Add a frame; errors unless it matches the first in geometry, CFA, levels and ISO.
    pub fn add(&mut self, img: &RawImage) -> Result<()> {
        // Compare metadata without the pixel data.
        let probe = RawImage {
            width: img.width,
            height: img.height,
            data: vec![],
            meta: img.meta.clone(),
        };
        let mut first = RawImage {
            width: self.first.width,
            height: self.first.height,
            data: vec![],
            meta: self.first.meta.clone(),
        };
        first.meta.storage = None;
        check_same_capture(
            &first,
            &probe,
            SameCapture {
                iso: true,
                levels: true,
            },
        )?;
        img.validate()?;
        if img.data == self.first.data {
            return Err(Error::invalid(
                "frame is identical to the first frame of the burst (the same file twice?)",
            ));
        }
        self.add_unchecked(img);
        Ok(())
    }

    fn add_unchecked(&mut self, img: &RawImage) {
        let a = img.active_area();
        let (w, h) = (a.width(), a.height());
        let half = 2 * (self.frames % 2);
        for r in 0..h {
            let start = (r + a.top as usize) * img.width + a.left as usize;
            let Some(row) = img.data.get(start..start + w) else {
                continue;
            };
            for (c, &x) in row.iter().enumerate() {
                let i = r * w + c;
                let l = self.norm.linearize(x);
                if x == 0 || l >= self.norm.white {
                    self.clipped[i] = true;
                }
                let l = l as u64;
                self.sums[i][half] += l;
                self.sums[i][half + 1] += l * l;
            }
        }
        self.frames += 1;
    }

    /// Frames added so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Per-pixel mean and variance, binned. Errors with fewer than two frames.
    pub fn finish(self) -> Result<SourceStats> {
        let n = self.frames as u64;
        if n < MIN_BURST_FRAMES as u64 {
            return Err(Error::invalid(format!(
                "a burst needs at least {MIN_BURST_FRAMES} frames (split-half variance estimate), got {n}"
            )));
        }
        let bayer = self.first.bayer()?;
        let a = self.first.active_area();
        let (w, h) = (a.width(), a.height());
        let scale = self.norm.scale;
        let mut accs = vec![[Acc::default(); 4]; NBINS];
        let mut clipped = [0u64; 4];
        // Frames per half: even frames 0, 2, 4, ... and odd frames 1, 3, ...
        let ne = n.div_ceil(2);
        let no = n / 2;
        let split = no >= 2; // always true past the frame-count check
        let moments = |s: u64, ss: u64, k: u64| -> (f64, f64) {
            let (s, ss, kk) = (s as u128, ss as u128, k as u128);
            let var = (kk * ss - s * s) as f64 / (k * (k - 1)) as f64;
            (s as f64 / k as f64, var)
        };
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                let p = Bayer::position(r, c);
                if self.clipped[i] {
                    clipped[p] += 1;
                    continue;
                }
                let [se, sse, so, sso] = self.sums[i];
                let black = self.norm.black_at(r, c);
                let norm = |m: f64| (m - black) / scale;
                // (binning mean, measured mean, measured variance, dof)
                let mut samples: [(f64, f64, f64, f64); 2] = [(0.0, 0.0, 0.0, 0.0); 2];
                let used = if split {
                    let (me, ve) = moments(se, sse, ne);
                    let (mo, vo) = moments(so, sso, no);
                    samples[0] = (norm(mo), norm(me), ve, (ne - 1) as f64);
                    samples[1] = (norm(me), norm(mo), vo, (no - 1) as f64);
                    2
                } else {
                    let (m, v) = moments(se + so, sse + sso, n);
                    samples[0] = (norm(m), norm(m), v, (n - 1) as f64);
                    1
                };
                for (k, &(yb, ym, v, dof)) in samples[..used].iter().enumerate() {
                    if let Some(b) = bin_index(yb) {
                        let acc = &mut accs[b][p];
                        // Pixels are counted once (by the first half's binning).
                        acc.n += u64::from(k == 0);
                        acc.sy += ym * dof;
                        acc.sv += v / (scale * scale) * dof;
                        acc.sr += dof;
                    }
                }
            }
        }
        let bins = std::array::from_fn(|p| {
            accs.iter()
                .filter(|a| a[p].sr > 0.0)
                .map(|a| {
                    let a = a[p];
                    BinStat {
                        mean: a.sy / a.sr,
                        var: a.sv / a.sr,
                        dof: a.sr,
                        pixels: a.n,
                    }
                })
                .collect()
        });
        Ok(SourceStats {
            kind: "burst",
            iso: iso_of(&self.first)?,
            bayer,
            black: self.first.meta.levels.black_max(),
            white: self.first.meta.levels.white,
            camera: camera_of(&self.first),
            bins,
            clipped,
            frames: self.frames,
        })
    }
}

/// Binned residual statistics of a clean/noisy pair (ISO and levels from the noisy frame).
/// Both are normalized with their own levels, so the clean may be a `merge` output (levels
/// scaled by the frame count); they must share geometry and CFA. The residual variance also
/// holds the clean frame's own noise: a merge of N frames at the noisy frame's ISO adds 1/N.
pub fn pair_stats(clean: &RawImage, noisy: &RawImage) -> Result<SourceStats> {
    check_same_capture(
        clean,
        noisy,
        SameCapture {
            iso: false,
            levels: false,
        },
    )?;
    let norm = Normalizer::new(noisy)?;
    let cnorm = Normalizer::new(clean)?;
    let bayer = noisy.bayer()?;
    let iso = iso_of(noisy)?;
    if clean.data == noisy.data {
        return Err(Error::invalid(
            "the clean and noisy frames are identical: no residual to measure",
        ));
    }
    let a = noisy.active_area();
    let (w, h) = (a.width(), a.height());
    let mut accs = vec![[Acc::default(); 4]; NBINS];
    let mut clipped = [0u64; 4];
    for r in 0..h {
        let start = (r + a.top as usize) * noisy.width + a.left as usize;
        let (Some(rc), Some(rn)) = (
            clean.data.get(start..start + w),
            noisy.data.get(start..start + w),
        ) else {
            continue;
        };
        for (c, (&xc, &xn)) in rc.iter().zip(rn).enumerate() {
            let p = Bayer::position(r, c);
            let (lc, ln) = (cnorm.linearize(xc), norm.linearize(xn));
            if xc == 0 || xn == 0 || lc >= cnorm.white || ln >= norm.white {
                clipped[p] += 1;
                continue;
            }
            let y = cnorm.normalize(xc, r, c);
            if let Some(b) = bin_index(y) {
                let yn = norm.normalize(xn, r, c);
                let d = yn - y;
                let acc = &mut accs[b][p];
                acc.n += 1;
                // Binned by the clean value, but the bin's intensity is the mean of the NOISY
                // values: their noise is independent of the binning, so it estimates
                // E[x | bin] without the shrinkage the clean frame's own noise would bring.
                acc.sy += yn;
                acc.sr += d;
                acc.srr += d * d;
            }
        }
    }
    let bins = std::array::from_fn(|p| {
        accs.iter()
            .filter(|a| a[p].n > 1)
            .map(|a| {
                let a = a[p];
                let nf = a.n as f64;
                BinStat {
                    mean: a.sy / nf,
                    var: ((a.srr - a.sr * a.sr / nf) / (nf - 1.0)).max(0.0),
                    dof: nf - 1.0,
                    pixels: a.n,
                }
            })
            .collect()
    });
    Ok(SourceStats {
        kind: "pair",
        iso,
        bayer,
        black: noisy.meta.levels.black_max(),
        white: noisy.meta.levels.white,
        camera: camera_of(noisy),
        bins,
        clipped,
        frames: 2,
    })
}

/// Iteratively reweighted fit of `var = S mean + O` over bins (see module docs).
/// Returns the fit and the bins used.
pub fn fit_bins(bins: &[(BinStat, (f64, f64))]) -> Result<(LineFit, Vec<BinStat>)> {
    let usable: Vec<&(BinStat, (f64, f64))> = bins
        .iter()
        .filter(|(b, _)| b.pixels >= MIN_BIN_PIXELS && b.dof >= MIN_BIN_DOF)
        .collect();
    if usable.is_empty() {
        return Err(Error::invalid(format!(
            "no intensity bin has {MIN_BIN_PIXELS} unclipped pixels: the frames are too small or all clipped"
        )));
    }
    if usable.iter().all(|(b, _)| b.var <= 0.0) {
        return Err(Error::invalid(
            "zero variance across the frames at every intensity: identical frames or a noise-free source, nothing to fit",
        ));
    }
    let pos_mean = usable
        .iter()
        .map(|(b, _)| b.var)
        .filter(|v| *v > 0.0)
        .sum::<f64>()
        / usable.len() as f64;
    let floor = pos_mean * 1e-4;
    let mut sel: Vec<&(BinStat, (f64, f64))> = usable.clone();
    // First pass: weights from the measured variances themselves.
    let mut model: Option<LineFit> = None;
    for iter in 0..8 {
        if let Some(m) = model {
            // Drop bins too close to a clipping bound, by the current model.
            sel = usable
                .iter()
                .copied()
                .filter(|(b, (lo, hi))| {
                    let sd = (m.slope * b.mean + m.intercept).max(floor).sqrt();
                    b.mean - CLIP_MARGIN_SIGMAS * sd > *lo && b.mean + CLIP_MARGIN_SIGMAS * sd < *hi
                })
                .collect();
        }
        let x: Vec<f64> = sel.iter().map(|(b, _)| b.mean).collect();
        let y: Vec<f64> = sel.iter().map(|(b, _)| b.var).collect();
        let w: Vec<f64> = sel
            .iter()
            .map(|(b, _)| {
                let v = match model {
                    Some(m) => m.slope * b.mean + m.intercept,
                    None => b.var,
                }
                .max(floor);
                b.dof / (2.0 * v * v)
            })
            .collect();
        let f = wls_line(&x, &y, &w).map_err(|e| {
            Error::invalid(format!(
                "cannot fit the noise model ({e}): the scene needs a range of intensities (a ramp or textured scene, not a flat field)"
            ))
        })?;
        let done = model.is_some_and(|m| {
            (m.slope - f.slope).abs() <= 1e-9 * f.slope.abs().max(1e-30)
                && (m.intercept - f.intercept).abs() <= 1e-9 * f.intercept.abs().max(1e-30)
        });
        model = Some(f);
        if done && iter > 1 {
            break;
        }
    }
    let f = model.ok_or_else(|| Error::invalid("noise fit did not run"))?;
    Ok((f, sel.into_iter().map(|(b, _)| *b).collect()))
}

/// Fit one ISO from its sources (bursts and/or pairs of the same camera levels and CFA).
pub fn fit_iso(sources: &[SourceStats]) -> Result<IsoModel> {
    let first = sources
        .first()
        .ok_or_else(|| Error::invalid("no burst or pair to fit"))?;
    for s in sources {
        if s.bayer != first.bayer || s.black != first.black || s.white != first.white {
            return Err(Error::invalid(format!(
                "inputs at ISO {} disagree in CFA pattern or levels ({} black {} white {} vs {} black {} white {})",
                first.iso, s.bayer, s.black, s.white, first.bayer, first.black, first.white
            )));
        }
    }
    let scale = first.scale();
    let q = 1.0 / (12.0 * scale * scale);
    let mut positions = Vec::with_capacity(4);
    for p in 0..4 {
        let bins: Vec<(BinStat, (f64, f64))> = sources
            .iter()
            .flat_map(|s| s.bins[p].iter().map(move |b| (*b, s.bounds())))
            .collect();
        let (f, used) = fit_bins(&bins).map_err(|e| {
            Error::invalid(format!("ISO {} position {}: {}", first.iso, p, e.root()))
        })?;
        let s = f.slope;
        let o = f.intercept - q;
        let beta1 = s * scale;
        let beta2 = o * scale * scale - first.black * beta1;
        let color = match first.bayer.color_at(p / 2, p % 2) {
            0 => "R",
            1 => "G",
            _ => "B",
        };
        positions.push(PositionFit {
            position: p,
            color: color.into(),
            s,
            o,
            s_stderr: Some(f.slope_se),
            o_stderr: Some(f.intercept_se),
            beta1,
            beta2,
            r2: Some(f.r2),
            chi2_reduced: Some(if f.dof > 0 {
                f.chi2 / f.dof as f64
            } else {
                0.0
            }),
            bins: used.len(),
            pixels: used.iter().map(|b| b.pixels).sum(),
            clipped_pixels: sources.iter().map(|s| s.clipped[p]).sum(),
        });
    }
    let kinds: std::collections::BTreeSet<&str> = sources.iter().map(|s| s.kind).collect();
    Ok(IsoModel {
        iso: first.iso,
        positions: std::array::from_fn(|p| [positions[p].s, positions[p].o]),
        source: kinds.into_iter().collect::<Vec<_>>().join("+"),
        black: first.black,
        white: first.white,
        inputs: sources.len(),
        quantization_variance_removed: q,
        fits: positions,
    })
}

/// Models from the NoiseProfile tags of DNGs: one per ISO (files at the same ISO are
/// averaged). A profile with one (S, O) pair applies to all planes; with three, per colour.
pub fn from_noise_profiles(imgs: &[(String, &RawImage)]) -> Result<Vec<IsoModel>> {
    let mut by_iso: BTreeMap<u32, Vec<(String, &RawImage)>> = BTreeMap::new();
    for (name, img) in imgs {
        let iso = iso_of(img).map_err(|e| e.in_file(name))?;
        by_iso.entry(iso).or_default().push((name.clone(), img));
    }
    let mut out = vec![];
    for (iso, files) in by_iso {
        let mut sum = [[0.0f64; 2]; 4];
        let (mut black, mut white, mut bayer0) = (0.0, 0.0, None);
        for (name, img) in &files {
            let bayer = img.bayer().map_err(|e| e.in_file(name))?;
            if bayer0.is_some_and(|b| b != bayer) {
                return Err(Error::invalid(format!(
                    "CFA pattern {bayer} differs from the other files at ISO {iso}"
                ))
                .in_file(name));
            }
            bayer0 = Some(bayer);
            black = img.meta.levels.black_max();
            white = img.meta.levels.white;
            let np = img
                .meta
                .noise_profile
                .as_ref()
                .filter(|v| !v.is_empty())
                .ok_or_else(|| Error::invalid("the DNG has no NoiseProfile tag").in_file(name))?;
            let params = NoiseParams::from_dng_profile(np, bayer).map_err(|e| e.in_file(name))?;
            for (acc, so) in sum.iter_mut().zip(params.positions) {
                acc[0] += so[0];
                acc[1] += so[1];
            }
        }
        let bayer = bayer0.ok_or_else(|| Error::invalid("no files"))?;
        let k = files.len() as f64;
        let scale = white - black;
        let fits: Vec<PositionFit> = (0..4)
            .map(|p| {
                let (s, o) = (sum[p][0] / k, sum[p][1] / k);
                let beta1 = s * scale;
                PositionFit {
                    position: p,
                    color: ["R", "G", "B"][bayer.color_at(p / 2, p % 2) as usize % 3].into(),
                    s,
                    o,
                    s_stderr: None,
                    o_stderr: None,
                    beta1,
                    beta2: o * scale * scale - black * beta1,
                    r2: None,
                    chi2_reduced: None,
                    bins: 0,
                    pixels: 0,
                    clipped_pixels: 0,
                }
            })
            .collect();
        out.push(IsoModel {
            iso,
            positions: std::array::from_fn(|p| [fits[p].s, fits[p].o]),
            source: "noise_profile".into(),
            black,
            white,
            inputs: files.len(),
            quantization_variance_removed: 0.0,
            fits,
        });
    }
    Ok(out)
}

/// `S = c ISO` (least squares through the origin) and `O = a + b ISO^2` (least squares)
/// per position across ISO models; `None` with fewer than two distinct ISOs.
pub fn fit_iso_laws(models: &[IsoModel]) -> Option<IsoLaws> {
    if models.len() < 2 {
        return None;
    }
    let isos: Vec<f64> = models.iter().map(|m| m.iso as f64).collect();
    let iso2: Vec<f64> = isos.iter().map(|i| i * i).collect();
    let mut laws = IsoLaws {
        s_per_iso: [0.0; 4],
        o_at_iso0: [0.0; 4],
        o_per_iso2: [0.0; 4],
        isos: models.iter().map(|m| m.iso).collect(),
    };
    for p in 0..4 {
        let s: Vec<f64> = models.iter().map(|m| m.positions[p][0]).collect();
        let o: Vec<f64> = models.iter().map(|m| m.positions[p][1]).collect();
        laws.s_per_iso[p] = ls_through_origin(&isos, &s)?;
        let f = wls_line(&iso2, &o, &vec![1.0; o.len()]).ok()?;
        laws.o_at_iso0[p] = f.intercept;
        laws.o_per_iso2[p] = f.slope;
    }
    Some(laws)
}

/// Assemble the model file from measured sources and other models (NoiseProfile tags, image
/// estimates), recording `camera`. Measured ISOs take precedence over the others at the
/// same ISO, and earlier others over later ones (returned as warnings).
pub fn build_model(
    sources: Vec<SourceStats>,
    profiles: Vec<IsoModel>,
    camera: Option<CameraId>,
) -> Result<(NoiseModelFile, Diagnostics)> {
    let mut by_iso: BTreeMap<u32, Vec<SourceStats>> = BTreeMap::new();
    for s in sources {
        by_iso.entry(s.iso).or_default().push(s);
    }
    let mut models: BTreeMap<u32, IsoModel> = BTreeMap::new();
    for (iso, srcs) in &by_iso {
        models.insert(*iso, fit_iso(srcs)?);
    }
    let mut warnings = Diagnostics::new();
    for p in profiles {
        match models.entry(p.iso) {
            std::collections::btree_map::Entry::Occupied(o) => warnings.warn(
                Code::CalibrateIsoOverlap,
                format!(
                    "ISO {}: the {} model takes precedence over the {} one",
                    p.iso,
                    o.get().source,
                    p.source
                ),
            ),
            std::collections::btree_map::Entry::Vacant(v) => {
                v.insert(p);
            }
        }
    }
    if models.is_empty() {
        return Err(Error::invalid(
            "nothing to calibrate: give --burst, --pair, --from-noise-profile or --from-image",
        ));
    }
    let isos: Vec<IsoModel> = models.into_values().collect();
    for m in &isos {
        for f in &m.fits {
            if f.o < 0.0 || f.s < 0.0 {
                warnings.warn(Code::CalibrateNegativeParameter, format!(
                    "ISO {} position {}: negative parameter (S {:.3e}, O {:.3e}); synth clamps variances at 0",
                    m.iso, f.position, f.s, f.o
                ));
            }
        }
    }
    Ok((
        NoiseModelFile {
            format: NOISE_FORMAT.into(),
            units: NOISE_UNITS.into(),
            source: format!(
                "day2night {} calibrate noise{}",
                crate::VERSION,
                camera
                    .as_ref()
                    .map(|c| format!(" ({})", c.label()))
                    .unwrap_or_default()
            ),
            camera,
            iso_laws: fit_iso_laws(&isos),
            isos,
        },
        warnings,
    ))
}

#[cfg(test)]
pub(crate) mod tests;
