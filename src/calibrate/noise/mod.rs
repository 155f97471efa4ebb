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

mod burst;
mod fit;
mod pair;
mod profiles;

pub use burst::BurstAccumulator;
pub use fit::{build_model, fit_bins, fit_iso, fit_iso_laws};
pub use pair::pair_stats;
pub use profiles::from_noise_profiles;

use crate::error::{Error, Result};
use crate::raw::{Bayer, RawImage};

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

#[cfg(test)]
pub(crate) mod tests;
