//! Display geometry of renders: the DNG DefaultCrop, the TIFF/EXIF Orientation, and the
//! map between displayed pixels and active-area sites.

use super::rgb::RgbImage;
use crate::raw::RawMeta;
use rayon::prelude::*;

/// DefaultCrop rectangle (x, y, width, height) within an active area of `w x h`: origin and
/// size rounded to whole pixels and clamped inside the area; the whole area when absent.
pub fn default_crop(meta: &RawMeta, w: usize, h: usize) -> (usize, usize, usize, usize) {
    let fin = |v: f64| {
        if v.is_finite() {
            v.max(0.0).round() as usize
        } else {
            0
        }
    };
    let (x0, y0) = meta
        .default_crop_origin
        .map(|o| {
            (
                fin(o[0]).min(w.saturating_sub(1)),
                fin(o[1]).min(h.saturating_sub(1)),
            )
        })
        .unwrap_or((0, 0));
    let (cw, ch) = meta
        .default_crop_size
        .map(|s| (fin(s[0]), fin(s[1])))
        .unwrap_or((w, h));
    let cw = cw.clamp(1, w - x0);
    let ch = ch.clamp(1, h - y0);
    (x0, y0, cw, ch)
}

/// Crop (DefaultCrop) then orient (Orientation 1..8) an image of the active area.
pub fn apply_geometry(rgb: RgbImage, meta: &RawMeta, crop: bool, orient: bool) -> RgbImage {
    let rgb = if crop && rgb.width > 0 && rgb.height > 0 {
        let (x0, y0, cw, ch) = default_crop(meta, rgb.width, rgb.height);
        if (x0, y0, cw, ch) == (0, 0, rgb.width, rgb.height) {
            rgb
        } else {
            // In place: row y moves from 3 * ((y + y0) * width + x0) down to 3 * y * cw,
            // never after its source, so rows copied in order do not overwrite unread data
            // (no second full-size buffer; same pixels as copying into a new image).
            let mut rgb = rgb;
            for y in 0..ch {
                let s = 3 * ((y + y0) * rgb.width + x0);
                rgb.data.copy_within(s..s + 3 * cw, 3 * y * cw);
            }
            rgb.data.truncate(3 * cw * ch);
            rgb.width = cw;
            rgb.height = ch;
            rgb
        }
    } else {
        rgb
    };
    if orient && (2..=8).contains(&meta.orientation) {
        orient_image(&rgb, meta.orientation)
    } else {
        // Orientation 1 (or unknown): the image as it is, not a copy.
        rgb
    }
}

/// The pixel `(x, y)` of a `w` x `h` image that lands at `(xo, yo)` of the image displayed
/// with the TIFF/EXIF Orientation code `orientation` (1..8; anything else is 1). For codes
/// 5-8 the displayed image is `h` x `w`. `(xo, yo)` must be inside the displayed image.
#[inline]
pub fn oriented_source(
    orientation: u16,
    w: usize,
    h: usize,
    xo: usize,
    yo: usize,
) -> (usize, usize) {
    match orientation {
        2 => (w - 1 - xo, yo),
        3 => (w - 1 - xo, h - 1 - yo),
        4 => (xo, h - 1 - yo),
        5 => (yo, xo),
        6 => (yo, h - 1 - xo),
        7 => (w - 1 - yo, h - 1 - xo),
        8 => (w - 1 - yo, xo),
        _ => (xo, yo),
    }
}

/// Where the pixels of a rendered image come from: [`super::render()`]'s DefaultCrop and
/// Orientation of an active area, as a map from displayed pixels to active-area sites (for
/// drawing things computed in active-area coordinates, e.g. light masks, over a render).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DisplayGeometry {
    x0: usize,
    y0: usize,
    cw: usize,
    ch: usize,
    orientation: u16,
}

impl DisplayGeometry {
    /// The geometry a render applies (crop and orientation on) to an active area of
    /// `aw` x `ah` described by `meta`.
    pub fn new(meta: &RawMeta, aw: usize, ah: usize) -> DisplayGeometry {
        let (x0, y0, cw, ch) = default_crop(meta, aw, ah);
        let orientation = if (2..=8).contains(&meta.orientation) {
            meta.orientation
        } else {
            1
        };
        DisplayGeometry {
            x0,
            y0,
            cw,
            ch,
            orientation,
        }
    }
    /// The whole active area, unrotated.
    pub fn identity(aw: usize, ah: usize) -> DisplayGeometry {
        DisplayGeometry {
            x0: 0,
            y0: 0,
            cw: aw,
            ch: ah,
            orientation: 1,
        }
    }
    /// Width and height of the displayed image.
    pub fn dims(&self) -> (usize, usize) {
        if self.orientation >= 5 {
            (self.ch, self.cw)
        } else {
            (self.cw, self.ch)
        }
    }
    /// Active-area (column, row) shown at displayed pixel `(xo, yo)` (clamped into the
    /// displayed image).
    pub fn active_site(&self, xo: usize, yo: usize) -> (usize, usize) {
        let (dw, dh) = self.dims();
        let (xo, yo) = (xo.min(dw.saturating_sub(1)), yo.min(dh.saturating_sub(1)));
        let (x, y) = oriented_source(self.orientation, self.cw, self.ch, xo, yo);
        (self.x0 + x, self.y0 + y)
    }
    /// Displayed position of the active-area point (column `u`, row `v`) in continuous
    /// pixel coordinates (pixel `(c, r)` covers `[c, c+1) x [r, r+1)`); `None` when the
    /// point is outside the DefaultCrop.
    pub fn display_point(&self, u: f64, v: f64) -> Option<(f64, f64)> {
        let (x, y) = (u - self.x0 as f64, v - self.y0 as f64);
        let (w, h) = (self.cw as f64, self.ch as f64);
        if !(0.0..=w).contains(&x) || !(0.0..=h).contains(&y) {
            return None;
        }
        Some(match self.orientation {
            2 => (w - x, y),
            3 => (w - x, h - y),
            4 => (x, h - y),
            5 => (y, x),
            6 => (h - y, x),
            7 => (h - y, w - x),
            8 => (y, w - x),
            _ => (x, y),
        })
    }
}

/// Transform an image for display according to the TIFF/EXIF Orientation code (1..8;
/// anything else is treated as 1).
pub fn orient_image(img: &RgbImage, orientation: u16) -> RgbImage {
    let (w, h) = (img.width, img.height);
    if !(2..=8).contains(&orientation) {
        return img.clone();
    }
    let swap = orientation >= 5;
    let (ow, oh) = if swap { (h, w) } else { (w, h) };
    let mut out = RgbImage::new(ow, oh);
    out.data
        .par_chunks_mut(3 * ow.max(1))
        .enumerate()
        .for_each(|(yo, row)| {
            for (xo, px) in row.chunks_exact_mut(3).enumerate() {
                let (x, y) = oriented_source(orientation, w, h, xo, yo);
                let s = 3 * (y * w + x);
                px.copy_from_slice(&img.data[s..s + 3]);
            }
        });
    out
}
