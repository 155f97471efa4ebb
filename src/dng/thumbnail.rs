//! Small 8-bit RGB thumbnail rendered from a raw image, for the IFD0 preview that precedes a
//! raw image stored in a SubIFD (`--raw-ifd sub`).
//!
//! Rendering is deliberately simple and deterministic: LinearizationTable, black subtraction
//! (per site, deltas included) and white scaling; 2x2 CFA binning over the active area into
//! one RGB pixel (greens averaged); white balance by AsShotNeutral; camera -> sRGB through
//! the inverse of ColorMatrix1 when it is invertible (otherwise the camera RGB is used);
//! box downscale so that the longer side is at most `max_side`; sRGB gamma; 8 bits.

use crate::color::matrix3::{self, diag, mul, Mat3, IDENTITY};
use crate::color::srgb;
use crate::color::xyz::XYZ_TO_SRGB;
use crate::error::{Error, Result};
use crate::raw::RawImage;

/// An 8-bit RGB thumbnail.
#[derive(Debug, Clone, PartialEq)]
pub struct Thumbnail {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height * 3` bytes, RGB, row-major.
    pub rgb: Vec<u8>,
}

/// Inverse of ColorMatrix1 when its determinant is at least 1e-12 in magnitude (an absolute
/// test, unlike [`matrix3::inverse`]'s relative one: the thumbnails written so far keep
/// their bytes).
fn inverse_cm1(v: &[f64]) -> Option<Mat3> {
    let m = matrix3::from_row_major(v)?;
    let det = matrix3::determinant(&m);
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    Some(matrix3::inverse_with_determinant(&m, det))
}

/// A linear value as an 8-bit sRGB code (clipped to [0, 1]; NaN gives 0).
fn srgb_gamma(x: f64) -> u8 {
    (srgb::oetf_f64(x.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8
}

/// Render a thumbnail whose longer side is at most `max_side` (>= 1).
pub fn render(img: &RawImage, max_side: usize) -> Result<Thumbnail> {
    img.validate()?;
    let bayer = img.bayer()?;
    let a = img.active_area();
    let (aw, ah) = (a.width(), a.height());
    // Binned (half-resolution) grid; a 1-pixel-wide active area still gives one cell.
    let bw = (aw / 2).max(1);
    let bh = (ah / 2).max(1);
    let scale = bw.max(bh).div_ceil(max_side.max(1)).max(1);
    let tw = bw.div_ceil(scale);
    let th = bh.div_ceil(scale);
    let lev = &img.meta.levels;
    let lut = img.meta.linearization_table.as_deref();
    let neutral = img.meta.as_shot_neutral.unwrap_or([1.0, 1.0, 1.0]);
    // camera (white balanced) -> sRGB: XYZ_TO_SRGB * inv(CM1) * diag(neutral), normalised so
    // that camera white (1,1,1 after balance) maps to sRGB white.
    let xyz_to_srgb = matrix3::from_row_major(&XYZ_TO_SRGB).unwrap_or(IDENTITY);
    let cam_to_srgb = img
        .meta
        .color
        .color_matrix1
        .as_deref()
        .and_then(inverse_cm1)
        .map(|ci| {
            let m = mul(&xyz_to_srgb, &mul(&ci, &diag(neutral)));
            m.map(|row| {
                let s: f64 = row.iter().sum();
                if s.abs() > 1e-9 {
                    row.map(|v| v / s)
                } else {
                    row
                }
            })
        })
        .filter(|m| m.iter().flatten().all(|v| v.is_finite()))
        .unwrap_or(IDENTITY);
    let top = a.top as usize;
    let left = a.left as usize;
    let value = |r: usize, c: usize| -> f64 {
        // (r, c) in active-area coordinates, clamped inside.
        let r = r.min(ah - 1);
        let c = c.min(aw - 1);
        let raw = img.data[(top + r) * img.width + left + c];
        let lin = match lut {
            Some(t) if !t.is_empty() => t[(raw as usize).min(t.len() - 1)] as f64,
            _ => raw as f64,
        };
        let black = lev.black_at(r, c);
        ((lin - black) / (lev.white - black)).max(0.0)
    };
    let mut rgb = Vec::with_capacity(tw * th * 3);
    for ty in 0..th {
        for tx in 0..tw {
            let mut acc = [0.0f64; 3];
            let mut cnt = [0usize; 3];
            for by in ty * scale..((ty + 1) * scale).min(bh) {
                for bx in tx * scale..((tx + 1) * scale).min(bw) {
                    for dy in 0..2 {
                        for dx in 0..2 {
                            let (r, c) = (by * 2 + dy, bx * 2 + dx);
                            let ch = bayer.color_at(r, c) as usize;
                            acc[ch] += value(r, c);
                            cnt[ch] += 1;
                        }
                    }
                }
            }
            let mut cam = [0.0; 3];
            for ch in 0..3 {
                let n = neutral[ch];
                let n = if n > 0.0 && n.is_finite() { n } else { 1.0 };
                cam[ch] = if cnt[ch] > 0 {
                    acc[ch] / cnt[ch] as f64 / n
                } else {
                    0.0
                };
            }
            for row in &cam_to_srgb {
                let v: f64 = (0..3).map(|k| row[k] * cam[k]).sum();
                rgb.push(srgb_gamma(v));
            }
        }
    }
    if rgb.len() != tw * th * 3 {
        return Err(Error::malformed("thumbnail size mismatch"));
    }
    Ok(Thumbnail {
        width: tw,
        height: th,
        rgb,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    #[test]
    fn grey_raw_gives_grey_thumbnail_within_size() {
        let mut meta = RawMeta::new_bayer(Bayer::GRBG, 12, 100.0, 4095.0);
        meta.as_shot_neutral = Some([0.5, 1.0, 0.8]);
        let (w, h) = (600usize, 202usize);
        // A grey scene: each site = black + neutral * level.
        let bayer = Bayer::GRBG;
        let data = (0..w * h)
            .map(|i| {
                let (r, c) = (i / w, i % w);
                let n = meta.as_shot_neutral.unwrap()[bayer.color_at(r, c) as usize];
                (100.0 + n * 1000.0) as u16
            })
            .collect();
        let img = RawImage {
            width: w,
            height: h,
            data,
            meta,
        };
        let t = render(&img, 256).unwrap();
        assert!(t.width <= 256 && t.height <= 256);
        assert_eq!(t.width, 150);
        assert_eq!(t.rgb.len(), t.width * t.height * 3);
        for px in t.rgb.chunks(3) {
            let (mx, mn) = (px.iter().max().unwrap(), px.iter().min().unwrap());
            assert!(mx - mn <= 2, "not grey: {px:?}");
        }
        let one = RawImage {
            width: 1,
            height: 1,
            data: vec![500],
            meta: RawMeta::new_bayer(Bayer::RGGB, 12, 100.0, 4095.0),
        };
        let t = render(&one, 256).unwrap();
        assert_eq!((t.width, t.height), (1, 1));
    }
}
