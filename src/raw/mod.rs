//! The in-memory raw image: a CFA mosaic of `u16` samples plus its metadata, and the
//! geometry/level helpers every stage shares (Bayer phase, ActiveArea, per-site black).

pub mod camera;
pub mod crop;
pub mod from_parts;
pub mod meta;
pub mod rows;

use crate::error::{Error, Result};
pub use meta::RawMeta;
use serde::{Deserialize, Serialize};

/// Colour of a CFA site: 0 = red, 1 = green, 2 = blue (DNG CFAPlaneColor order R,G,B).
pub type CfaColor = u8;

/// A 2x2 Bayer pattern, row-major, relative to the ActiveArea's top-left corner
/// (DNG spec: CFAPattern is relative to the active area).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Bayer(pub [CfaColor; 4]);

impl Bayer {
    /// RGGB.
    pub const RGGB: Bayer = Bayer([0, 1, 1, 2]);
    /// GRBG.
    pub const GRBG: Bayer = Bayer([1, 0, 2, 1]);
    /// GBRG.
    pub const GBRG: Bayer = Bayer([1, 2, 0, 1]);
    /// BGGR.
    pub const BGGR: Bayer = Bayer([2, 1, 1, 0]);
    /// All four phases.
    pub const ALL: [Bayer; 4] = [Bayer::RGGB, Bayer::GRBG, Bayer::GBRG, Bayer::BGGR];

    /// Colour at (row, col) of the active area.
    #[inline]
    pub fn color_at(&self, row: usize, col: usize) -> CfaColor {
        self.0[((row & 1) << 1) | (col & 1)]
    }
    /// 2x2 position index (0..4, row-major) of (row, col) in the active area.
    #[inline]
    pub fn position(row: usize, col: usize) -> usize {
        ((row & 1) << 1) | (col & 1)
    }
    /// Build from four colour codes; error unless exactly one R, two G, one B with the two
    /// greens on a diagonal.
    pub fn from_pattern(p: [u8; 4]) -> Result<Bayer> {
        let b = Bayer(p);
        if Bayer::ALL.contains(&b) {
            Ok(b)
        } else {
            Err(Error::unsupported(format!(
                "CFA pattern {:?} is not a Bayer pattern (need one red, two diagonal greens, one blue)",
                p
            )))
        }
    }
    /// Name such as "RGGB".
    pub fn name(&self) -> String {
        self.0
            .iter()
            .map(|&c| match c {
                0 => 'R',
                1 => 'G',
                2 => 'B',
                _ => '?',
            })
            .collect()
    }
}

impl std::fmt::Display for Bayer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// Rectangle in stored-image pixel coordinates (DNG ActiveArea order: top, left, bottom, right).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rect {
    /// First row.
    pub top: u32,
    /// First column.
    pub left: u32,
    /// One past the last row.
    pub bottom: u32,
    /// One past the last column.
    pub right: u32,
}

impl Rect {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.right.saturating_sub(self.left) as usize
    }
    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.bottom.saturating_sub(self.top) as usize
    }
}

/// A raw CFA image as stored in the DNG: `width x height` samples (the whole stored image,
/// including any masked border outside ActiveArea), row-major, plus all metadata.
///
/// Sample values are *stored* values: before LinearizationTable and black subtraction.
#[derive(Debug, Clone, PartialEq)]
pub struct RawImage {
    /// Stored width (ImageWidth).
    pub width: usize,
    /// Stored height (ImageLength).
    pub height: usize,
    /// `width * height` samples, row-major.
    pub data: Vec<u16>,
    /// Everything the DNG said about the image.
    pub meta: RawMeta,
}

impl RawImage {
    /// The active area (whole image when the DNG has no ActiveArea tag).
    pub fn active_area(&self) -> Rect {
        self.meta.active_area.unwrap_or(Rect {
            top: 0,
            left: 0,
            bottom: self.height as u32,
            right: self.width as u32,
        })
    }
    /// The Bayer pattern, or an error naming why the CFA is not a 2x2 RGB Bayer mosaic.
    pub fn bayer(&self) -> Result<Bayer> {
        self.meta.bayer()
    }
    /// Sample at stored (row, col).
    #[inline]
    pub fn get(&self, row: usize, col: usize) -> u16 {
        self.data[row * self.width + col]
    }
    /// Check internal consistency: data length, active area inside the image, levels sane.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::malformed("image has zero width or height"));
        }
        let spp = self.meta.samples_per_pixel();
        if self.data.len() != self.width * self.height * spp {
            return Err(Error::malformed(format!(
                "pixel buffer holds {} samples, expected {}x{}{}",
                self.data.len(),
                self.width,
                self.height,
                if spp == 1 {
                    String::new()
                } else {
                    format!("x{spp}")
                }
            )));
        }
        check_layout(self.width, self.height, &self.meta)
    }
}

/// The checks of [`RawImage::validate`] that do not need the samples: a `width` x `height`
/// image with metadata `meta` has its active area inside it and sane levels.
pub fn check_layout(width: usize, height: usize, meta: &RawMeta) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::malformed("image has zero width or height"));
    }
    let a = meta.active_area.unwrap_or(Rect {
        top: 0,
        left: 0,
        bottom: height as u32,
        right: width as u32,
    });
    if a.top >= a.bottom
        || a.left >= a.right
        || a.bottom as usize > height
        || a.right as usize > width
    {
        return Err(Error::malformed(format!(
            "ActiveArea {},{},{},{} is empty or outside the {}x{} image",
            a.top, a.left, a.bottom, a.right, width, height
        )));
    }
    meta.levels.validate(a.width(), a.height())?;
    match &meta.linear_raw {
        Some(l) => l.validate(&meta.levels),
        None => Ok(()),
    }
}

/// Black and white levels per DNG chapter 5, in linearized units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Levels {
    /// BlackLevelRepeatDim (rows, cols); (1, 1) when absent.
    pub black_repeat: (usize, usize),
    /// BlackLevel values, `rows * cols` of them, row-major (one sample per pixel for CFA).
    pub black: Vec<f64>,
    /// BlackLevelDeltaH: one value per active-area column (empty when absent).
    pub black_delta_h: Vec<f64>,
    /// BlackLevelDeltaV: one value per active-area row (empty when absent).
    pub black_delta_v: Vec<f64>,
    /// WhiteLevel (first sample; CFA images have one).
    pub white: f64,
}

impl Levels {
    /// Black level at active-area (row, col), deltas included.
    #[inline]
    pub fn black_at(&self, row: usize, col: usize) -> f64 {
        let (rr, rc) = self.black_repeat;
        let mut b = self.black[(row % rr) * rc + (col % rc)];
        if let Some(d) = self.black_delta_h.get(col) {
            b += d;
        }
        if let Some(d) = self.black_delta_v.get(row) {
            b += d;
        }
        b
    }
    /// The largest black level over the plane (deltas included): the spec's `black_max`.
    pub fn black_max(&self) -> f64 {
        let base = self.black.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let dh = self.black_delta_h.iter().cloned().fold(0.0, f64::max);
        let dv = self.black_delta_v.iter().cloned().fold(0.0, f64::max);
        base + dh + dv
    }
    /// Error unless the levels are finite, the shapes match the active area, and
    /// black_max < white ("black >= white" is a clear error, not a NaN).
    pub fn validate(&self, active_w: usize, active_h: usize) -> Result<()> {
        let (rr, rc) = self.black_repeat;
        if rr == 0 || rc == 0 || self.black.len() != rr * rc {
            return Err(Error::malformed(format!(
                "BlackLevel has {} values for BlackLevelRepeatDim {}x{}",
                self.black.len(),
                rr,
                rc
            )));
        }
        if !self.black_delta_h.is_empty() && self.black_delta_h.len() != active_w {
            return Err(Error::malformed(format!(
                "BlackLevelDeltaH has {} values, active width is {}",
                self.black_delta_h.len(),
                active_w
            )));
        }
        if !self.black_delta_v.is_empty() && self.black_delta_v.len() != active_h {
            return Err(Error::malformed(format!(
                "BlackLevelDeltaV has {} values, active height is {}",
                self.black_delta_v.len(),
                active_h
            )));
        }
        let all = self
            .black
            .iter()
            .chain(&self.black_delta_h)
            .chain(&self.black_delta_v)
            .chain(std::iter::once(&self.white));
        if all.clone().any(|v| !v.is_finite()) {
            return Err(Error::malformed(
                "black or white level is not a finite number",
            ));
        }
        let bmax = self.black_max();
        if bmax >= self.white {
            // Name only the tags that make the black level: the deltas when present.
            let deltas: Vec<&str> = [
                ("BlackLevelDeltaH", &self.black_delta_h),
                ("BlackLevelDeltaV", &self.black_delta_v),
            ]
            .iter()
            .filter(|(_, d)| !d.is_empty())
            .map(|(n, _)| *n)
            .collect();
            let with = if deltas.is_empty() {
                String::new()
            } else {
                format!(" with {}", deltas.join(" and "))
            };
            return Err(Error::malformed(format!(
                "black level {} >= white level {} (BlackLevel{with} against WhiteLevel)",
                bmax, self.white
            )));
        }
        Ok(())
    }
}
