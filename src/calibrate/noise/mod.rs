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

mod fit;

pub use fit::{build_model, fit_bins, fit_iso, fit_iso_laws};

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

#[cfg(test)]
pub(crate) mod tests;
