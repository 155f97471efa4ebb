//! Crops: a rectangle of the active area that a synthesis computes instead of the whole
//! frame (the Python package's training crops). The plan is always the full frame's; a
//! crop only limits what is computed.

use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;
use serde::{Deserialize, Serialize};

/// A rectangle of the active area, in active-area sample coordinates (row `top`, column
/// `left`, `height` rows of `width` samples). Even `top` and `left` keep the CFA phase: the
/// crop's 2x2 pattern is the frame's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Crop {
    /// First row.
    pub top: usize,
    /// First column.
    pub left: usize,
    /// Rows.
    pub height: usize,
    /// Columns.
    pub width: usize,
}

impl Crop {
    /// The whole active area of `width x height`.
    pub fn whole(width: usize, height: usize) -> Crop {
        Crop {
            top: 0,
            left: 0,
            height,
            width,
        }
    }

    /// Error unless the crop is non-empty, has even offsets and lies inside an active
    /// area of `aw x ah`.
    pub fn check(&self, aw: usize, ah: usize) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(format!(
                "crop {}x{} is empty",
                self.height, self.width
            )));
        }
        if !self.top.is_multiple_of(2) || !self.left.is_multiple_of(2) {
            return Err(Error::invalid(format!(
                "crop offset ({}, {}) must be even (it keeps the CFA phase)",
                self.top, self.left
            )));
        }
        let bottom = self.top.checked_add(self.height);
        let right = self.left.checked_add(self.width);
        if bottom.is_none_or(|b| b > ah) || right.is_none_or(|r| r > aw) {
            return Err(Error::invalid(format!(
                "crop (top {}, left {}, height {}, width {}) is outside the {}x{} active area",
                self.top, self.left, self.height, self.width, ah, aw
            )));
        }
        Ok(())
    }

    /// Rows `top..top + height`.
    pub fn rows(&self) -> std::ops::Range<usize> {
        self.top..self.top + self.height
    }

    /// Columns `left..left + width`.
    pub fn cols(&self) -> std::ops::Range<usize> {
        self.left..self.left + self.width
    }

    /// The crop grown by `pad` samples on every side (rounded out to even offsets), cut to
    /// an active area of `aw x ah`.
    pub fn grown(&self, pad: usize, aw: usize, ah: usize) -> Crop {
        let pad = pad + pad % 2;
        let top = self.top.saturating_sub(pad);
        let left = self.left.saturating_sub(pad);
        let bottom = (self.top + self.height + pad).min(ah);
        let right = (self.left + self.width + pad).min(aw);
        Crop {
            top,
            left,
            height: bottom - top,
            width: right - left,
        }
    }

    /// The samples of this crop out of a plane holding the crop `outer` (row-major,
    /// `outer.width` per row); `self` must lie inside `outer`.
    pub fn cut_from<T: Copy>(&self, outer: &Crop, plane: &[T]) -> Vec<T> {
        let (dy, dx) = (self.top - outer.top, self.left - outer.left);
        let mut out = Vec::with_capacity(self.width * self.height);
        for r in 0..self.height {
            let s = (dy + r) * outer.width + dx;
            out.extend_from_slice(&plane[s..s + self.width]);
        }
        out
    }
}

/// The metadata of the crop `crop` of an image described by `meta`, as a raw image of its
/// own: no ActiveArea or DefaultCrop (the crop is all active), the BlackLevel pattern
/// re-phased to the crop's origin and BlackLevelDeltaH/V cut to its columns and rows,
/// opcode lists (frame geometry) dropped. The 2x2 CFA phase is unchanged (even offsets).
pub fn crop_meta(meta: &RawMeta, crop: &Crop) -> RawMeta {
    let mut m = meta.clone();
    m.active_area = None;
    m.default_crop_origin = None;
    m.default_crop_size = None;
    m.opcode_lists = [None, None, None];
    let l = &meta.levels;
    let (rr, rc) = l.black_repeat;
    if rr > 0 && rc > 0 && l.black.len() == rr * rc {
        m.levels.black = (0..rr * rc)
            .map(|i| l.black[((i / rc + crop.top) % rr) * rc + (i % rc + crop.left) % rc])
            .collect();
    }
    let cut = |v: &[f64], r: std::ops::Range<usize>| -> Vec<f64> {
        v.get(r).map(<[f64]>::to_vec).unwrap_or_default()
    };
    if !l.black_delta_h.is_empty() {
        m.levels.black_delta_h = cut(&l.black_delta_h, crop.cols());
    }
    if !l.black_delta_v.is_empty() {
        m.levels.black_delta_v = cut(&l.black_delta_v, crop.rows());
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks() {
        let c = Crop {
            top: 2,
            left: 4,
            height: 6,
            width: 8,
        };
        c.check(12, 8).unwrap();
        assert!(c.check(11, 8).unwrap_err().to_string().contains("outside"));
        let odd = Crop { left: 3, ..c };
        assert!(odd
            .check(100, 100)
            .unwrap_err()
            .to_string()
            .contains("even"));
        let empty = Crop { width: 0, ..c };
        assert!(empty.check(100, 100).is_err());
        let huge = Crop {
            width: usize::MAX,
            ..c
        };
        assert!(huge.check(100, 100).is_err());
    }

    #[test]
    fn grown_and_cut() {
        let c = Crop {
            top: 2,
            left: 2,
            height: 3,
            width: 3,
        };
        let g = c.grown(2, 6, 6);
        assert_eq!(
            g,
            Crop {
                top: 0,
                left: 0,
                height: 6,
                width: 6
            }
        );
        let g1 = c.grown(1, 100, 100);
        assert_eq!((g1.top, g1.left, g1.height, g1.width), (0, 0, 7, 7));
        let plane: Vec<u32> = (0..36).collect();
        assert_eq!(c.cut_from(&g, &plane), [14, 15, 16, 20, 21, 22, 26, 27, 28]);
    }
}
